#!/usr/bin/env python3
"""A Blender extension repository: the extension zips and the index.json Blender reads.

    scripts/extension-repo.py ZIP... --out DIR [--tool blender_ext.py]

Copies each extension zip (one a platform: its manifest's `platforms` says which) into DIR and
writes DIR/index.json with Blender's own extension tooling: `blender_ext.py server-generate`,
the script behind `blender --command extension server-generate`, which the official bpy wheels
carry (bpy/<version>/scripts/addons_core/bl_pkg/cli/blender_ext.py) and which runs as a plain
Python script. It is taken from the bpy venv of scripts/bpy-env.sh (the series TOOL_SERIES,
made if missing), or from --tool. Each zip first passes the same tool's `validate`.

An artist adds DIR's URL (https://..., or file:///studio/share/dqjulia) under Preferences > Get
Extensions > Repositories; Blender downloads index.json, offers the zip of its own platform, and
offers a newer version as an update once DIR holds it (docs/blender.md, "Installing").

DIR may hold other files (a release folder does): server-generate lists every .zip in the folder
it is given, so it runs in a private folder holding only these zips, and its index.json (whose
archive URLs are relative: ./NAME.zip) is then copied beside them. Each file is written under a
temporary name and renamed into place, the index last, so a reader never sees an index naming a
zip that is not there yet. server-generate lists the zips in the folder's directory order, which
differs between file systems; the list is sorted by file name and written back in the tool's own
format (json, indent 2), so the same zips give the same bytes.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The bpy series whose tooling writes the index (the newest tested; tests/blender/repository_test.py
# syncs its index in every tested version).
TOOL_SERIES = "5.3"
INDEX = "index.json"


def fail(message):
    raise SystemExit("extension-repo.py: " + message)


def find_tool():
    """(python, blender_ext.py) from the bpy venv of TOOL_SERIES, made by scripts/bpy-env.sh if missing."""
    bpy_env = os.path.join(ROOT, "scripts", "bpy-env.sh")
    printed = subprocess.run([bpy_env, "--print", TOOL_SERIES], capture_output=True, text=True)
    if printed.returncode != 0:
        print(
            "extension-repo.py: making the bpy %s venv for Blender's extension tooling" % TOOL_SERIES, file=sys.stderr
        )
        if subprocess.run([bpy_env, TOOL_SERIES]).returncode != 0:
            fail("could not make the bpy %s venv (scripts/bpy-env.sh %s)" % (TOOL_SERIES, TOOL_SERIES))
        printed = subprocess.run([bpy_env, "--print", TOOL_SERIES], capture_output=True, text=True, check=True)
    python = printed.stdout.strip()
    venv = os.path.dirname(os.path.dirname(python))
    found = []
    for folder, _dirs, names in os.walk(os.path.join(venv, "lib")):
        if "blender_ext.py" in names and folder.endswith(os.path.join("bl_pkg", "cli")):
            found.append(os.path.join(folder, "blender_ext.py"))
    if len(found) != 1:
        fail("expected one bl_pkg/cli/blender_ext.py in %s, found %s" % (venv, found or "none"))
    return python, found[0]


def run_tool(python, tool, *args):
    result = subprocess.run([python, tool, *args], capture_output=True, text=True)
    return result.returncode, (result.stdout + result.stderr).strip()


def check_is_extension(path):
    """A readable zip holding a blender_manifest.toml (the tool's validate checks the rest)."""
    try:
        with zipfile.ZipFile(path) as archive:
            names = [name for name in archive.namelist() if name.endswith("blender_manifest.toml")]
    except (OSError, zipfile.BadZipFile) as error:
        fail("%s is not a readable zip: %s" % (path, error))
    if not names:
        fail("%s holds no blender_manifest.toml: not a Blender extension" % path)


def check_platforms(entries):
    """Zips of one id and version must name disjoint platforms, each at least one: Blender offers
    the one of its platform, and a zip without `platforms` claims them all."""
    seen = {}
    for entry in entries:
        platforms = entry.get("platforms")
        name = entry["archive_url"]
        if not platforms:
            if len(entries) > 1:
                fail("%s names no platforms (so every platform) beside other zips" % name)
            continue
        for platform in platforms:
            key = (entry["id"], entry["version"], platform)
            if key in seen:
                fail("%s and %s are both %s %s for %s" % (seen[key], name, entry["id"], entry["version"], platform))
            seen[key] = name


def write_file(source, target):
    """Copies source to target through a temporary name in target's folder."""
    folder = os.path.dirname(target)
    handle, temporary = tempfile.mkstemp(prefix=".%s." % os.path.basename(target), dir=folder)
    os.close(handle)
    try:
        shutil.copyfile(source, temporary)
        os.chmod(temporary, 0o644)
        os.replace(temporary, target)
    except BaseException:
        os.unlink(temporary)
        raise


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="extension-repo.py",
        description="Copy Blender extension zips into DIR and write DIR/index.json with Blender's own tooling.",
    )
    parser.add_argument("zips", nargs="+", metavar="ZIP", help="extension zips, one a platform")
    parser.add_argument("--out", required=True, metavar="DIR", help="the repository folder (made if missing)")
    parser.add_argument(
        "--tool",
        default="",
        metavar="BLENDER_EXT_PY",
        help="Blender's bl_pkg/cli/blender_ext.py (default: from the bpy %s venv of scripts/bpy-env.sh)" % TOOL_SERIES,
    )
    args = parser.parse_args(argv)

    names = [os.path.basename(path) for path in args.zips]
    for path in args.zips:
        if not path.endswith(".zip") or not os.path.isfile(path):
            fail("%s is not a .zip file" % path)
        check_is_extension(path)
    if len(set(names)) != len(names):
        fail("two zips have one name: %s" % names)
    if INDEX in names:
        fail("a zip cannot be named %s" % INDEX)
    python, tool = (sys.executable, args.tool) if args.tool else find_tool()

    for path in args.zips:
        status, output = run_tool(python, tool, "validate", path)
        if status != 0:
            fail("Blender's validation refuses %s:\n%s" % (path, output))

    with tempfile.TemporaryDirectory(prefix="extension-repo-") as stage:
        for path in args.zips:
            shutil.copyfile(path, os.path.join(stage, os.path.basename(path)))
        status, output = run_tool(python, tool, "server-generate", "--repo-dir", stage)
        index_path = os.path.join(stage, INDEX)
        if status != 0 or not os.path.isfile(index_path):
            fail("Blender's server-generate failed (exit %d):\n%s" % (status, output))
        with open(index_path, encoding="utf-8") as handle:
            text = handle.read()
        index = json.loads(text)
        if json.dumps(index, indent=2) != text:
            fail("server-generate's index.json is not in the format this script writes back (json, indent 2)")
        entries = index.get("data", [])
        listed = sorted(entry.get("archive_url", "") for entry in entries)
        if listed != sorted("./" + name for name in names):
            fail("server-generate listed %s, not every zip given (%s):\n%s" % (listed, names, output))
        check_platforms(entries)
        entries.sort(key=lambda entry: entry["archive_url"])
        with open(index_path, "w", encoding="utf-8") as handle:
            json.dump(index, handle, indent=2)

        os.makedirs(args.out, exist_ok=True)
        for name in names:
            write_file(os.path.join(stage, name), os.path.join(args.out, name))
        write_file(index_path, os.path.join(args.out, INDEX))
    for entry in entries:
        print(
            "%s %s %s: %s (%d bytes)"
            % (
                entry["id"],
                entry["version"],
                ",".join(entry.get("platforms", ["any"])),
                entry["archive_url"][2:],
                entry["archive_size"],
            )
        )
    print("wrote %s" % os.path.join(args.out, INDEX))


if __name__ == "__main__":
    main()
