#!/usr/bin/env python3
"""Writes the licence files every dqjulia package carries, for one target (the build runs it into
build/licenses/ and build-windows/licenses/):

  LICENSE                   dqjulia's own licence (GPL-3.0-or-later)
  THIRD-PARTY-NOTICES.txt   what the binaries contain, then each component's licence and notice
                            files as its Debian source has them, and our patches to it
  THIRD-PARTY.json          the component list: name, version, licence (SPDX), Debian source
                            package and upstream tarball, our patches, the artifacts holding it

from third_party/components.json (the one list) and the licence files scripts/build-deps.sh
installed into the deps prefix (share/licenses/<folder>/, with a SOURCE record each).

Usage: notices.py --source DIR --deps PREFIX --target linux-x64|windows-x64 --out DIR
"""

import argparse
import json
import os
import sys
import textwrap
from pathlib import Path

ARTIFACTS = {
    "linux-x64": {"library": "libdqjulia.so", "command": "dqjulia"},
    "windows-x64": {"library": "dqjulia.dll", "command": "dqjulia.exe"},
}
RULE = "=" * 100


def fail(message):
    print("notices.py: " + message, file=sys.stderr)
    sys.exit(1)


def components_for(source, target):
    """The components of third_party/components.json that the target's binaries contain."""
    data = json.loads((source / "third_party" / "components.json").read_text(encoding="utf-8"))
    return data["project"], [c for c in data["components"] if target in c["in"]]


def licence_files(deps, component):
    """The component's folder in the deps prefix: its SOURCE record and its licence files."""
    folder = deps / "share" / "licenses" / component["licenses"]
    if not folder.is_dir():
        fail(
            "%s has no licence files in %s: the deps prefix is older than the licences "
            "(rebuild it with scripts/build-deps.sh)" % (component["name"], folder)
        )
    record = (folder / "SOURCE").read_text(encoding="utf-8").strip()
    files = sorted(p for p in folder.iterdir() if p.name != "SOURCE")
    if not files:
        fail("%s: no licence file in %s" % (component["name"], folder))
    return record, files


def component_entry(source, deps, component, target):
    record, _ = licence_files(deps, component)
    fields = dict(line.split(": ", 1) for line in record.splitlines() if ": " in line)
    return {
        "name": component["name"],
        "version": component["version"],
        "license": component["license"],
        "homepage": component["homepage"],
        "debian_source": component["debian_source"],
        "source": fields,
        "patches": [Path(p).name for p in component.get("patches", [])],
        "in": [ARTIFACTS[target][artifact] for artifact in component["in"][target]],
    }


def notices_text(source, deps, project, components, target, version):
    names = ARTIFACTS[target]
    headers = [c["name"] for c in components if target == "linux-x64" and c.get("linux_package")]
    listed = ", ".join(headers[:-1]) + " and " + headers[-1] if len(headers) > 1 else "".join(headers)
    packaged = ", as are the headers of %s here" % listed if headers else ""
    intro = (
        "dqjulia is free software under the %s licence (the file LICENSE beside this one). Its binaries "
        "(%s, the library with the C ABI; %s, the command) contain the components below, linked in "
        "statically or compiled in through their headers. The libraries are built from the upstream source in "
        "Debian 12's source package named here (`apt-get source NAME`), changed only by the patches listed, "
        "whose text follows the component's licence. The toolchain's runtime libraries and Boost's headers are "
        "Debian 12's packages%s. dqjulia's source release holds those patches and the scripts that build "
        "everything." % (project["license"], names["library"], names["command"], packaged)
    )
    lines = ["dqjulia %s for %s: third-party notices" % (version, target), "", textwrap.fill(intro, 96), ""]
    rows = [("Component", "Version", "Licence (SPDX)", "Debian source", "In")]
    for c in components:
        where = ", ".join(names[a] for a in c["in"][target])
        rows.append((c["name"], c["version"], c["license"], c["debian_source"], where))
    widths = [max(len(row[i]) for row in rows) for i in range(4)]
    for row in rows:
        lines.append("  " + "  ".join(cell.ljust(width) for cell, width in zip(row, widths)) + "  " + row[4])
    credits = [textwrap.fill(c["notice"], 96) for c in components if c.get("notice")]
    if credits:
        lines += [""] + credits
    for c in components:
        record, files = licence_files(deps, c)
        lines += ["", RULE, "%s %s (%s)" % (c["name"], c["version"], c["license"]), c["homepage"], record]
        if c.get("patches"):
            lines.append("Changed by dqjulia: " + ", ".join(Path(p).name for p in c["patches"]) + " (below)")
        lines.append(RULE)
        for path in files:
            text = path.read_text(encoding="utf-8", errors="replace").rstrip()
            lines += ["", "--- %s: %s ---" % (c["name"], path.name), "", text]
        for patch in c.get("patches", []):
            text = (source / patch).read_text(encoding="utf-8").rstrip()
            lines += ["", "--- %s: dqjulia's patch %s ---" % (c["name"], Path(patch).name), "", text]
    return "\n".join(line.rstrip() for line in "\n".join(lines).split("\n")) + "\n"


def write(path, data):
    """Replaces the file whole (a reader never sees half of it)."""
    temporary = path.with_name(path.name + ".tmp")
    temporary.write_bytes(data)
    os.replace(temporary, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", required=True, type=Path, help="dqjulia's source tree")
    parser.add_argument("--deps", required=True, type=Path, help="the deps prefix (scripts/build-deps.sh)")
    parser.add_argument("--target", required=True, choices=sorted(ARTIFACTS))
    parser.add_argument("--out", required=True, type=Path)
    args = parser.parse_args()

    version = (args.source / "VERSION").read_text(encoding="utf-8").strip()
    project, components = components_for(args.source, args.target)
    notices = notices_text(args.source, args.deps, project, components, args.target, version)
    listing = {
        "project": project["name"],
        "version": version,
        "license": project["license"],
        "target": args.target,
        "components": [component_entry(args.source, args.deps, c, args.target) for c in components],
    }
    args.out.mkdir(parents=True, exist_ok=True)
    write(args.out / "LICENSE", (args.source / "LICENSE").read_bytes())
    write(args.out / "THIRD-PARTY-NOTICES.txt", notices.encode("utf-8"))
    write(args.out / "THIRD-PARTY.json", (json.dumps(listing, indent=2, ensure_ascii=False) + "\n").encode("utf-8"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
