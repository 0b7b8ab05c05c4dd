#!/usr/bin/env python3
"""Makes a release's files from a Linux and a Windows build tree of this checkout (the packaging
half of scripts/release.sh, which makes the two builds first; tests/release runs it on the test
command's own build/ and build-windows/):

  dqjulia-VERSION-linux-x64.tar.gz        the install trees (`cmake --install --strip`): bin/ lib/
  dqjulia-VERSION-windows-x64.zip         (with the CMake package and dqjulia.pc) include/
                                          share/dqjulia/ (POV-Ray include, examples) share/doc/dqjulia/
                                          (README, CHANGELOG, LICENSE, notices, component list)
  dqjulia_blender-VERSION-linux-x64.zip   the builds' Blender extension zips under their final names
  dqjulia_blender-VERSION-windows-x64.zip
  index.json                              the extension repository (scripts/extension-repo.py)
  *.whl, dqjulia-VERSION.tar.gz           the wheels and the sdist (scripts/build-wheels.py)
  THIRD-PARTY.json                        the component list of both targets
  SHA256SUMS                              of every other file, as sha256sum writes it

Everything is reproducible: archives by scripts/pack.py, with SOURCE_DATE_EPOCH (by default the
commit's time) as every entry's time.

Usage: dist.py --linux-build DIR --windows-build DIR --out DIR [--no-wheels] [--no-index]
OUT must not exist; on failure nothing of it is left.
"""

import argparse
import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

SOURCE = Path(__file__).resolve().parent.parent
PLATFORMS = {
    "linux-x64": {"archive": "tar.gz", "addon_zip": "dist/dqjulia_blender.zip"},
    "windows-x64": {"archive": "zip", "addon_zip": "dist/dqjulia_blender-windows-x64.zip"},
}


class DistError(Exception):
    pass


def log(message):
    print("dist: " + message, flush=True)


def run(*command, **options):
    result = subprocess.run([str(part) for part in command], capture_output=True, text=True, **options)
    if result.returncode != 0:
        raise DistError(
            "%s failed (exit %d):\n%s%s"
            % (" ".join(map(str, command)), result.returncode, result.stdout, result.stderr)
        )
    return result.stdout


def cache_value(build, name):
    """A variable of the build tree's CMakeCache.txt."""
    cache = build / "CMakeCache.txt"
    if not cache.is_file():
        raise DistError("%s is not a configured build tree (no CMakeCache.txt)" % build)
    for line in cache.read_text(encoding="utf-8", errors="replace").splitlines():
        key, _, value = line.partition("=")
        if key.split(":")[0] == name:
            return value
    return None


def check_build(build, platform, version):
    """The build tree is of this checkout, of this version and for this platform, and built."""
    home = cache_value(build, "CMAKE_HOME_DIRECTORY")
    if home is None or Path(home).resolve() != SOURCE:
        raise DistError("%s is a build of %s, not of this checkout (%s)" % (build, home, SOURCE))
    built_version = cache_value(build, "CMAKE_PROJECT_VERSION")
    if built_version != version:
        raise DistError(
            "%s is a build of version %s, the checkout's VERSION is %s: build it again"
            % (build, built_version, version)
        )
    windows = cache_value(build, "CMAKE_SYSTEM_NAME") == "Windows"
    if windows != (platform == "windows-x64"):
        raise DistError("%s is not a %s build" % (build, platform))
    zip_path = build / PLATFORMS[platform]["addon_zip"]
    if not zip_path.is_file():
        raise DistError("%s is missing: build %s first" % (zip_path, build))


def install_tree(build, stage, name):
    """`cmake --install --strip` of the build into stage/name: the archive's one top folder."""
    tree = stage / name
    run("cmake", "--install", build, "--prefix", tree, "--strip")
    return tree


def pack(kind, output, folder):
    run(sys.executable, SOURCE / "scripts" / "pack.py", kind, output, folder)


def sha256(path):
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def make(args, out, stage, version):
    builds = {"linux-x64": args.linux_build, "windows-x64": args.windows_build}
    for platform, build in builds.items():
        check_build(build, platform, version)

    addon_zips = []
    for platform, build in builds.items():
        name = "dqjulia-%s-%s" % (version, platform)
        log("installing %s into %s" % (build, name))
        tree = install_tree(build, stage, name)
        kind = PLATFORMS[platform]["archive"]
        pack(kind, out / ("%s.%s" % (name, kind)), tree)
        log("wrote %s.%s" % (name, kind))
        addon = stage / ("dqjulia_blender-%s-%s.zip" % (version, platform))
        shutil.copyfile(build / PLATFORMS[platform]["addon_zip"], addon)
        addon_zips.append(addon)

    if args.no_index:
        log("no index.json (--no-index)")
    else:
        tool = SOURCE / "scripts" / "extension-repo.py"
        # TODO(issue 36, blender helper): scripts/extension-repo.py writes index.json with Blender's
        # own `server-generate`; until it lands a release cannot be made without --no-index.
        if not tool.is_file():
            raise DistError(
                "scripts/extension-repo.py is missing (the extension repository's index.json): "
                "give --no-index to leave it out"
            )
        log("writing the extension repository's index.json")
        run(sys.executable, tool, *addon_zips, "--out", out)
        if not (out / "index.json").is_file():
            raise DistError("scripts/extension-repo.py wrote no index.json")
    for addon in addon_zips:  # extension-repo.py copies them; without it, here
        if not (out / addon.name).is_file():
            shutil.copyfile(addon, out / addon.name)
        if (out / addon.name).read_bytes() != addon.read_bytes():
            raise DistError("%s in the release differs from the build's extension zip" % addon.name)

    if args.no_wheels:
        log("no wheels (--no-wheels)")
    else:
        tool = SOURCE / "scripts" / "build-wheels.py"
        # TODO(issue 36, python helper): scripts/build-wheels.py writes the two wheels and the sdist;
        # until it lands a release cannot be made without --no-wheels.
        if not tool.is_file():
            raise DistError(
                "scripts/build-wheels.py is missing (the wheels and the sdist): give --no-wheels to leave them out"
            )
        log("writing the wheels and the sdist")
        run(
            sys.executable, tool, "--linux-build", args.linux_build, "--windows-build", args.windows_build, "--out", out
        )

    listing = {"project": "dqjulia", "version": version, "targets": {}}
    for platform, build in builds.items():
        target = json.loads((build / "licenses" / "THIRD-PARTY.json").read_text(encoding="utf-8"))
        listing["license"] = target["license"]
        listing["targets"][platform] = target["components"]
    (out / "THIRD-PARTY.json").write_text(json.dumps(listing, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")

    files = sorted(p.name for p in out.iterdir() if p.is_file() and p.name != "SHA256SUMS")
    (out / "SHA256SUMS").write_text("".join("%s  %s\n" % (sha256(out / name), name) for name in files))
    for name in files + ["SHA256SUMS"]:
        log("%10d  %s" % ((out / name).stat().st_size, name))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--linux-build", required=True, type=Path)
    parser.add_argument("--windows-build", required=True, type=Path)
    parser.add_argument("--out", required=True, type=Path)
    parser.add_argument("--no-wheels", action="store_true", help="leave out the wheels and the sdist")
    parser.add_argument("--no-index", action="store_true", help="leave out the extension repository's index.json")
    args = parser.parse_args()
    args.linux_build = args.linux_build.resolve()
    args.windows_build = args.windows_build.resolve()
    out = args.out.resolve()
    if out.exists():
        print("dist: %s exists already: give a new folder" % out, file=sys.stderr)
        return 2
    if "SOURCE_DATE_EPOCH" not in os.environ:  # every time stamp: the commit's
        try:
            stamp = run("git", "-C", SOURCE, "log", "-1", "--format=%ct").strip()
        except (DistError, OSError):
            stamp = ""
        if stamp:
            os.environ["SOURCE_DATE_EPOCH"] = stamp
    version = (SOURCE / "VERSION").read_text(encoding="utf-8").strip()
    stage = out.with_name(out.name + ".stage")
    shutil.rmtree(stage, ignore_errors=True)
    out.mkdir(parents=True)
    stage.mkdir()
    try:
        make(args, out, stage, version)
    except BaseException as error:  # interrupted too: nothing of OUT is left
        shutil.rmtree(out, ignore_errors=True)
        if not isinstance(error, (DistError, OSError)):
            raise
        print("dist: %s" % error, file=sys.stderr)
        return 1
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
