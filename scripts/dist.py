#!/usr/bin/env python3
"""Makes a release's files from a Linux and a Windows build tree of this checkout (the packaging
half of scripts/release.sh, which makes the two builds first; tests/release runs it on the test
command's own build/ and build-windows/):

  dqjulia-VERSION-linux-x64.tar.gz        the install trees (`cmake --install --strip`): bin/ (on
  dqjulia-VERSION-windows-x64.zip         Linux the glibc-floor launcher, the command itself in
                                          libexec/dqjulia/) lib/ (with the CMake package and
                                          dqjulia.pc) include/ share/dqjulia/ (POV-Ray include,
                                          examples) share/doc/dqjulia/ (README, CHANGELOG, LICENSE,
                                          notices, component list)
  dqjulia_blender-VERSION-linux-x64.zip   the builds' Blender extension zips under their final names
  dqjulia_blender-VERSION-windows-x64.zip
  index.json                              the extension repository (scripts/extension-repo.py)
  *.whl, dqjulia-VERSION.tar.gz           the wheels and the sdist (scripts/build-wheels.py)
  dqjulia-VERSION-docs.zip                the documentation site (scripts/build-docs.sh on the Linux
                                          build), with LICENSE and the notices of Sphinx's and the
                                          theme's files it carries
  THIRD-PARTY.json                        the component list of both targets
  SHA256SUMS                              of every other file, as sha256sum writes it

The version is VERSION's, checked against each build's. Everything is reproducible: the archives
by scripts/pack.py, the wheels by scripts/build-wheels.py, with SOURCE_DATE_EPOCH (by default the
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

from build_tree import SOURCE, BuildTreeError, cache_value, check_build
from pack import PackError, folder_members, source_date_epoch, write_tar_gz, write_zip

PLATFORMS = {
    "linux-x64": {"system": "Linux", "archive": "tar.gz", "addon_zip": "dist/dqjulia_blender.zip"},
    "windows-x64": {"system": "Windows", "archive": "zip", "addon_zip": "dist/dqjulia_blender-windows-x64.zip"},
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


def check_release_build(build, platform, version):
    """The build tree is of this checkout, for this platform, of this version, and built."""
    check_build(build, PLATFORMS[platform]["system"])
    built_version = cache_value(build, "CMAKE_PROJECT_VERSION")
    if built_version != version:
        raise DistError(
            "%s is a build of version %s, the checkout's VERSION is %s: build it again"
            % (build, built_version, version)
        )
    for needed in (PLATFORMS[platform]["addon_zip"], "licenses/THIRD-PARTY.json"):
        if not (build / needed).is_file():
            raise DistError("%s is missing: build %s first" % (build / needed, build))


def install_tree(build, stage, name):
    """`cmake --install --strip` of the build into stage/name: the archive's one top folder."""
    tree = stage / name
    run("cmake", "--install", build, "--prefix", tree, "--strip")
    return tree


def sha256(path):
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


# The packages whose files the built site carries (Sphinx's search and basic theme, Furo and the
# base it builds on, Pygments' highlighting styles): their licences go into the site's notices.
SITE_COMPONENTS = ("sphinx", "furo", "sphinx_basic_ng", "pygments")


def docs_site(linux_build, stage, out, version):
    """dqjulia-VERSION-docs.zip: the site built from the Linux build's command, one folder."""
    name = "dqjulia-%s-docs" % version
    site = stage / name
    run("bash", SOURCE / "scripts" / "build-docs.sh", linux_build, site)
    (site / ".buildinfo").unlink(missing_ok=True)  # Sphinx's incremental-build record (names this machine's paths)
    shutil.copyfile(SOURCE / "LICENSE", site / "LICENSE")
    venv = Path(run("bash", SOURCE / "scripts" / "tool-env.sh", "sphinx", "--print").strip()).parent.parent
    notices = ["The documentation site carries files of these packages, under their licences:\n"]
    for component in SITE_COMPONENTS:
        infos = sorted(venv.glob("lib/python3*/site-packages/%s-*.dist-info" % component))
        if len(infos) != 1:
            raise DistError("the sphinx venv holds %d copies of %s" % (len(infos), component))
        licences = sorted(
            p for p in infos[0].rglob("*") if p.is_file() and p.name.upper().startswith(("LICENSE", "COPYING"))
        )
        if not licences:
            raise DistError("%s has no licence file in %s" % (component, infos[0]))
        for licence in licences:
            notices.append(
                "\n==== %s (%s)\n\n%s"
                % (infos[0].name[: -len(".dist-info")], licence.name, licence.read_text(encoding="utf-8"))
            )
    (site / "THIRD-PARTY-NOTICES.txt").write_text("".join(notices), encoding="utf-8")
    write_zip(out / (name + ".zip"), folder_members(site), source_date_epoch())
    log("wrote %s.zip" % name)


def make(args, out, stage, version):
    builds = {"linux-x64": args.linux_build, "windows-x64": args.windows_build}
    for platform, build in builds.items():
        check_release_build(build, platform, version)

    addon_zips = []
    for platform, build in builds.items():
        name = "dqjulia-%s-%s" % (version, platform)
        log("installing %s into %s" % (build, name))
        tree = install_tree(build, stage, name)
        kind = PLATFORMS[platform]["archive"]
        writer = write_tar_gz if kind == "tar.gz" else write_zip
        writer(out / ("%s.%s" % (name, kind)), folder_members(tree), source_date_epoch())
        log("wrote %s.%s" % (name, kind))
        addon = stage / ("dqjulia_blender-%s-%s.zip" % (version, platform))
        shutil.copyfile(build / PLATFORMS[platform]["addon_zip"], addon)
        addon_zips.append(addon)

    if args.no_index:
        log("no index.json (--no-index)")
        for addon in addon_zips:
            shutil.copyfile(addon, out / addon.name)
    else:
        log("writing the extension repository (scripts/extension-repo.py): the zips and index.json")
        run(sys.executable, SOURCE / "scripts" / "extension-repo.py", *addon_zips, "--out", out)
    for addon in addon_zips:
        if (out / addon.name).read_bytes() != addon.read_bytes():
            raise DistError("%s in the release differs from the build's extension zip" % addon.name)

    if args.no_wheels:
        log("no wheels (--no-wheels)")
    else:
        log("writing the wheels and the sdist (scripts/build-wheels.py)")
        run(
            sys.executable,
            SOURCE / "scripts" / "build-wheels.py",
            "--linux-build",
            args.linux_build,
            "--windows-build",
            args.windows_build,
            "--out",
            out,
        )

    log("building the documentation site (scripts/build-docs.sh)")
    docs_site(args.linux_build, stage, out, version)

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
    if "SOURCE_DATE_EPOCH" not in os.environ:  # every time stamp: the commit's (build-wheels.py's too)
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
        if not isinstance(error, (DistError, BuildTreeError, PackError, OSError)):
            raise
        print("dist: %s" % error, file=sys.stderr)
        return 1
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
