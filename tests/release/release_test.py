"""The release tested as it is installed (label release): the test command's own Linux and
Windows builds packaged as scripts/release.sh packages them (scripts/dist.py), then each
package checked and used the way a user uses it.

  components  third_party/components.json against scripts/build-deps.sh (versions, patches,
              the Debian packages the Linux build takes headers from), the licence files in the
              deps prefixes, the notices, and the link maps: every file the library's and the
              command's links took is a listed component's (or glibc's, or ours), and every
              component listed for them was linked
  package     scripts/dist.py on build/ and build-windows/ into WORK/dist (the archives, the
              extension zips and index.json, the wheels and the sdist, THIRD-PARTY.json,
              SHA256SUMS): the fixture of the checks below and of release.archive_debian (the
              Linux archive in clean Debian 11, 12 and 13 roots: tests/cleanroom/archive_test.py)
  contents    both archives: exactly the files of an install tree, entries owned by root with one
              time stamp, no path of the build machine in any file; the Linux command and library
              need only glibc 2.34 and no search path, its launcher only glibc 2.2.5; the Windows
              ones only Windows' DLLs
  consumer    the Linux archive unpacked elsewhere (a folder with a space in its name): its
              command runs, and a C program built against it with find_package(dqjulia) and with
              pkg-config runs
  windows     the Windows archive unpacked: its dqjulia.exe renders, bakes and meshes under Wine
              the same as the Linux build (tests/windows/cli_test.py)
  licenses    every package (archives, extension zips, wheels, sdist) carries LICENSE and the
              notices of its platform; THIRD-PARTY.json lists the components of both

Usage: python3 release_test.py CHECK --source DIR --linux-build DIR --windows-build DIR --work DIR
       [--glibc-floor 2.34] [--emulator COMMAND...] (windows: the Wine runner)
"""

import argparse
import fnmatch
import json
import os
import re
import shutil
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report, skip_or_fail  # noqa: E402 (tests/common/check_report.py)

TARGETS = ("linux-x64", "windows-x64")
ARTIFACT_MAPS = {"library": "dqjulia.map", "command": "dqjulia_cli.map"}
NOTICES = ("LICENSE", "THIRD-PARTY-NOTICES.txt")


def run(command, **options):
    result = subprocess.run([str(part) for part in command], capture_output=True, text=True, **options)
    return result.returncode, result.stdout + result.stderr


def cache_value(build, name):
    for line in (build / "CMakeCache.txt").read_text(encoding="utf-8", errors="replace").splitlines():
        key, _, value = line.partition("=")
        if key.split(":")[0] == name:
            return value
    return None


def version_of(source):
    return (source / "VERSION").read_text(encoding="utf-8").strip()


def components(source):
    return json.loads((source / "third_party" / "components.json").read_text(encoding="utf-8"))


# --- components -------------------------------------------------------------------------------


def build_deps_facts(source):
    """What scripts/build-deps.sh fetches (Debian source -> upstream version), its cache key's
    versions, the patches it applies (Debian source -> patch file names) and the licence folders
    it fills."""
    text = (source / "scripts" / "build-deps.sh").read_text(encoding="utf-8")
    fetched = dict(re.findall(r"^\s*fetch (\S+) '[^_']+_([0-9][0-9.]*[0-9])", text, re.M))
    key = " ".join(re.findall(r'^\s*versions="([^"]*)"', text, re.M))
    applied = {}
    for match in re.finditer(r'patch -d "\$work/src/([^"]+)"[^<\n]*< "\$here/patches/([^"]+)"', text):
        folder, patch = match.groups()
        # "$fix" takes the words of the loop that holds the line: the last "for fix in" before it.
        loops = re.findall(r"^for fix in ([^;]+); do", text[: match.start()], re.M)
        names = [patch.replace("$fix", fix) for fix in loops[-1].split()] if "$fix" in patch else [patch]
        applied.setdefault(folder, []).extend(names)
    folders = set(re.findall(r"^\s*licences (\S+)", text, re.M))
    folders |= set(re.findall(r"^\s*system_licence (\S+)", text, re.M))
    return fetched, key, applied, folders


def link_inputs(map_path):
    """The files a link took, from its GNU ld map: the archives a member was taken from, and the
    objects and shared libraries loaded (paths normalised; relative ones are the build's)."""
    text = map_path.read_text(encoding="utf-8", errors="replace")
    members = text.split("Archive member included to satisfy reference by file (symbol)", 1)[-1]
    for end in (
        "\nAs-needed library",
        "\nAllocating common symbols",
        "\nDiscarded input sections",
        "\nMemory Configuration",
    ):
        members = members.split(end, 1)[0]
    used = set(re.findall(r"^([^\s(][^\n(]*\.a)\(", members, re.M))
    for loaded in re.findall(r"^LOAD (.+)$", text, re.M):
        if not loaded.endswith(".a"):
            used.add(loaded.strip())
    return {os.path.normpath(path) for path in used}


def owner_of(path, data, deps, build):
    """The component (or "glibc" or "dqjulia") a linked file belongs to; None if none claims it."""
    if not os.path.isabs(path) or path.startswith(str(build) + os.sep):
        return "dqjulia"
    owners = []
    for component in data["components"]:
        for pattern in component.get("files", []):
            if "/" in pattern:
                hit = fnmatch.fnmatch(path, pattern)
            else:  # a deps archive: by name, inside the deps prefix
                hit = path.startswith(str(deps) + os.sep) and fnmatch.fnmatch(os.path.basename(path), pattern)
            if hit:
                owners.append(component["name"])
    for system in data["system"]:
        if any(fnmatch.fnmatch(path, pattern) for pattern in system["files"]):
            owners.append("glibc")
    return owners[0] if len(owners) == 1 else (None if not owners else "ambiguous: " + ", ".join(owners))


def without_trailing_blanks(path):
    """A licence file's text as the notices hold it: no blanks at the ends of lines (notices.py)."""
    text = path.read_text(encoding="utf-8", errors="replace").strip()
    return "\n".join(line.rstrip() for line in text.split("\n"))


def check_components(args, checks):
    data = components(args.source)
    fetched, key, applied, folders = build_deps_facts(args.source)
    sources = {c["debian_source"] for c in data["components"]}
    strays = {folder: names for folder, names in applied.items() if folder not in sources}
    checks["every patch build-deps.sh applies is a listed component's (others: %s)" % strays] = not strays
    builds = {"linux-x64": args.linux_build, "windows-x64": args.windows_build}
    deps = {target: Path(cache_value(build, "DQJ_DEPS_PREFIX")) for target, build in builds.items()}

    for component in data["components"]:
        name, version, source_name = component["name"], component["version"], component["debian_source"]
        if source_name in fetched:
            in_key = any(token.endswith("-" + version) for token in re.split(r"[_\s]", key))
            what = "%s %s: build-deps.sh fetches %s %s, in its cache key" % (
                name,
                version,
                source_name,
                fetched[source_name],
            )
            checks[what] = fetched[source_name] == version and in_key
        checks["%s: build-deps.sh installs its licences (%s)" % (name, component["licenses"])] = (
            component["licenses"] in folders
        )
        package = component.get("linux_package")
        if package:
            status, installed = run(["dpkg-query", "-W", "-f", "${Version}", package])
            checks["%s: the Linux build's headers, %s %s, are version %s" % (name, package, installed, version)] = (
                status == 0 and installed.startswith(version)
            )
        patches = [Path(p).name for p in component.get("patches", [])]
        wanted = applied.get(source_name, [])
        if patches or wanted:
            checks["%s: the patches listed are those build-deps.sh applies %s" % (name, wanted)] = sorted(
                patches
            ) == sorted(wanted) and all((args.source / p).is_file() for p in component["patches"])
        for target in component["in"]:
            folder = deps[target] / "share" / "licenses" / component["licenses"]
            record = (folder / "SOURCE").read_text(encoding="utf-8") if (folder / "SOURCE").is_file() else ""
            texts = [p for p in folder.iterdir() if p.name != "SOURCE"] if folder.is_dir() else []
            # Debian's source (its .dsc's version, when the mirror had it), or its upstream tarball;
            # for a package of the build machine, the package and its source.
            # A package of the build machine: its own version may be the component's where its
            # source's is not (gcc-mingw-w64-base 12.2.0-14+25.2, of source gcc-mingw-w64 25.2).
            match = re.search(r"(?:source package: |\(source )(\S+) ([^\s)]+)", record)
            package = re.search(r"^Debian package: \S+ (\S+)", record, re.M)
            tarball = re.search(r"Upstream tarball: %s_%s\b" % (re.escape(source_name), re.escape(version)), record)
            from_source = (
                match is not None
                and match.group(1) == source_name
                and (
                    match.group(2).startswith(version) or (package is not None and package.group(1).startswith(version))
                )
            )
            what = "%s (%s): licence files %s, from %s" % (name, target, [p.name for p in texts], record.strip())
            checks[what] = bool(texts) and (from_source or tarball is not None)
            notices = (builds[target] / "licenses" / "THIRD-PARTY-NOTICES.txt").read_text(encoding="utf-8")
            missing = [p.name for p in texts if without_trailing_blanks(p) not in notices]
            checks["%s (%s): the notices hold its name and licence texts (missing: %s)" % (name, target, missing)] = (
                "%s %s (%s)" % (name, version, component["license"]) in notices and not missing
            )

    for target, build in builds.items():
        for artifact, map_name in ARTIFACT_MAPS.items():
            map_path = build / "linkmaps" / map_name
            if not map_path.is_file():
                checks["%s %s: link map %s" % (target, artifact, map_path)] = False
                continue
            owners = {}
            for path in link_inputs(map_path):
                owners.setdefault(owner_of(path, data, deps[target], build), []).append(path)
            unclaimed = sorted(owners.pop(None, []) + sum((v for k, v in owners.items() if "ambiguous" in k), []))
            what = "%s %s: every linked file is a listed component's (unclaimed: %s)" % (target, artifact, unclaimed)
            checks[what] = not unclaimed
            listed = {
                c["name"]
                for c in data["components"]
                if artifact in c["in"].get(target, []) and not c.get("header_only")
            }
            linked = set(owners) - {"dqjulia", "glibc"}
            checks["%s %s links %s" % (target, artifact, sorted(linked))] = linked == listed


# --- package ----------------------------------------------------------------------------------


def check_package(args, checks):
    dist = args.work / "dist"
    shutil.rmtree(dist, ignore_errors=True)
    command = [sys.executable, args.source / "scripts" / "dist.py", "--linux-build", args.linux_build]
    command += ["--windows-build", args.windows_build, "--out", dist]
    status, output = run(command)
    print(output)
    checks["scripts/dist.py: exit %d" % status] = status == 0
    version = version_of(args.source)
    expected = {
        "dqjulia-%s-linux-x64.tar.gz" % version,
        "dqjulia-%s-windows-x64.zip" % version,
        "dqjulia_blender-%s-linux-x64.zip" % version,
        "dqjulia_blender-%s-windows-x64.zip" % version,
        "index.json",
        "dqjulia-%s-py3-none-manylinux_2_34_x86_64.whl" % version,
        "dqjulia-%s-py3-none-win_amd64.whl" % version,
        "dqjulia-%s.tar.gz" % version,
        "dqjulia-%s-docs.zip" % version,
        "THIRD-PARTY.json",
        "SHA256SUMS",
    }
    present = {p.name for p in dist.iterdir()} if dist.is_dir() else set()
    checks["the release holds no file missing: %s" % sorted(expected - present)] = not expected - present
    checks["the release holds no other file: %s" % sorted(present - expected)] = not present - expected
    if (dist / "index.json").is_file():
        index = json.loads((dist / "index.json").read_text(encoding="utf-8"))
        listed = {(e.get("archive_url"), tuple(e.get("platforms", []))) for e in index.get("data", [])}
        wanted = {("./dqjulia_blender-%s-%s.zip" % (version, t), (t,)) for t in TARGETS}
        checks["index.json lists both extension zips, each for its platform: %s" % sorted(listed)] = listed == wanted
    if (dist / "SHA256SUMS").is_file():
        listed = [line.split("  ", 1) for line in (dist / "SHA256SUMS").read_text().splitlines()]
        files = sorted(p.name for p in dist.iterdir() if p.name != "SHA256SUMS")
        checks["SHA256SUMS lists every other file (%d)" % len(files)] = sorted(n for _, n in listed) == files
        status, output = run(["sha256sum", "--check", "--quiet", "SHA256SUMS"], cwd=dist)
        checks["sha256sum --check SHA256SUMS: %s" % (output.strip() or "all OK")] = status == 0


# --- contents ---------------------------------------------------------------------------------


def expected_tree(source, version, target):
    """The relative paths of an install tree of this target (files and symbolic links)."""
    data = "share/dqjulia/"
    doc = "share/doc/dqjulia/"
    paths = {
        "include/dqjulia/dqjulia.h",
        "include/dqjulia/export.h",
        "include/dqjulia/version.h",
        "lib/cmake/dqjulia/dqjuliaConfig.cmake",
        "lib/cmake/dqjulia/dqjuliaConfigVersion.cmake",
        "lib/cmake/dqjulia/dqjuliaTargets.cmake",
        "lib/cmake/dqjulia/dqjuliaTargets-release.cmake",
        "lib/pkgconfig/dqjulia.pc",
        data + "povray/dqjulia.inc",
        doc + "README.md",
        doc + "CHANGELOG.md",
        doc + "LICENSE",
        doc + "THIRD-PARTY-NOTICES.txt",
        doc + "THIRD-PARTY.json",
    }
    paths |= {data + "examples/" + p.name for p in (source / "examples").glob("*.json")}
    paths |= {data + "examples/povray/" + p.name for p in (source / "examples" / "povray").glob("*.pov")}
    major = version.split(".")[0]
    if target == "linux-x64":  # bin/dqjulia: the launcher of libexec/dqjulia/dqjulia (core/cli/launcher.c)
        paths |= {"bin/dqjulia", "libexec/dqjulia/dqjulia", "lib/libdqjulia.so", "lib/libdqjulia.so." + major}
        paths.add("lib/libdqjulia.so." + version)
    else:
        paths |= {"bin/dqjulia.exe", "bin/dqjulia.dll", "lib/libdqjulia.dll.a"}
    return paths


def archive_members(path):
    """{name: (kind, owner, mtime, mode, data)} of a .tar.gz or zip (kind: file, dir or link)."""
    members = {}
    if path.name.endswith(".tar.gz"):
        with tarfile.open(path) as archive:
            for info in archive.getmembers():
                kind = "dir" if info.isdir() else "link" if info.issym() else "file"
                data = archive.extractfile(info).read() if info.isfile() else info.linkname.encode()
                members[info.name] = (kind, (info.uid, info.gid, info.uname, info.gname), info.mtime, info.mode, data)
    else:
        with zipfile.ZipFile(path) as archive:
            for info in archive.infolist():
                kind = "dir" if info.is_dir() else "file"
                stamp = info.date_time
                members[info.filename.rstrip("/")] = (kind, None, stamp, info.external_attr >> 16, archive.read(info))
    return members


def forbidden_paths(args):
    """Paths of the build machine no packaged file may hold."""
    paths = {args.source, args.linux_build, args.windows_build, Path.home() / ".cache"}
    for build in (args.linux_build, args.windows_build):
        paths.add(Path(cache_value(build, "DQJ_DEPS_PREFIX")))
    return sorted({str(p.resolve()) for p in paths} | {str(p) for p in paths})


def check_archive(args, checks, dist, target, version):
    kind = "tar.gz" if target == "linux-x64" else "zip"
    top = "dqjulia-%s-%s" % (version, target)
    path = dist / ("%s.%s" % (top, kind))
    if not path.is_file():
        checks["%s exists" % path.name] = False
        return
    members = archive_members(path)
    print("%s: %d entries, %.1f MB" % (path.name, len(members), path.stat().st_size / 1e6))
    outside = sorted(n for n in members if n != top and not n.startswith(top + "/"))
    checks["%s: everything inside %s/ (outside: %s)" % (path.name, top, outside[:5])] = not outside
    present = {n[len(top) + 1 :] for n, m in members.items() if m[0] != "dir" and n.startswith(top + "/")}
    expected = expected_tree(args.source, version, target)
    checks["%s: no file missing (%s)" % (path.name, sorted(expected - present))] = not expected - present
    checks["%s: no other file (%s)" % (path.name, sorted(present - expected))] = not present - expected
    checks["%s: one time stamp on every entry" % path.name] = len({m[2] for m in members.values()}) == 1
    if kind == "tar.gz":
        owners = {m[1] for m in members.values()}
        checks["%s: every entry owned by root: %s" % (path.name, owners)] = owners == {(0, 0, "root", "root")}
    hits = []
    for forbidden in forbidden_paths(args):
        hits += [(n, forbidden) for n, m in members.items() if forbidden.encode() in m[4]]
    checks["%s: no file holds a path of the build machine: %s" % (path.name, hits[:5])] = not hits
    pc = members.get(top + "/lib/pkgconfig/dqjulia.pc")
    checks["%s: dqjulia.pc is relative to itself (${pcfiledir})" % path.name] = (
        pc is not None and b"prefix=${pcfiledir}/../.." in pc[4]
    )


def unpack(path, where):
    """Unpacks a release archive as a user does, into where; returns the top folder."""
    shutil.rmtree(where, ignore_errors=True)
    where.mkdir(parents=True)
    if path.name.endswith(".tar.gz"):
        with tarfile.open(path) as archive:
            if hasattr(tarfile, "tar_filter"):  # Python 3.11.4 and later: say which filter (no warning)
                archive.extractall(where, filter="tar")
            else:
                archive.extractall(where)
    else:
        with zipfile.ZipFile(path) as archive:
            archive.extractall(where)
            for info in archive.infolist():  # zipfile keeps no modes: as unzip does
                mode = info.external_attr >> 16 & 0o777
                if mode:
                    os.chmod(where / info.filename, mode)
    (top,) = list(where.iterdir())
    return top


def check_contents(args, checks):
    dist = require_dist(args)
    version = version_of(args.source)
    for target in TARGETS:
        check_archive(args, checks, dist, target, version)
    # The binaries, as unpacked: Linux's need only glibc's libraries (2.34 at most, the launcher
    # 2.2.5) and no search path; Windows' only Windows' DLLs and the C runtime, and the DLL exports
    # exactly the C ABI.
    linux = unpack(dist / ("dqjulia-%s-linux-x64.tar.gz" % version), args.work / "contents" / "linux")
    check_library = args.source / "tests" / "cleanroom" / "check_library.py"
    floor = args.glibc_floor
    for binary, glibc, extra in (
        ("libexec/dqjulia/dqjulia", floor, ["--program"]),
        ("bin/dqjulia", "2.2.5", ["--program"]),
        ("lib/libdqjulia.so", floor, []),
    ):
        status, output = run([sys.executable, check_library, linux / binary, "--glibc-floor", glibc, *extra])
        print(output)
        checks["%s: only glibc %s, no search path (check_library.py)" % (binary, glibc)] = status == 0
    windows = unpack(dist / ("dqjulia-%s-windows-x64.zip" % version), args.work / "contents" / "windows")
    objdump = shutil.which("x86_64-w64-mingw32-objdump")
    if not objdump:
        skip_or_fail("x86_64-w64-mingw32-objdump is missing (scripts/install-deps.sh installs MinGW-w64)")
    check_dll = args.source / "tests" / "windows" / "check_dll.py"
    binaries = [windows / "bin" / "dqjulia.dll", windows / "bin" / "dqjulia.exe"]
    status, output = run([sys.executable, check_dll, objdump, args.source, *binaries])
    print(output)
    checks["dqjulia.dll and dqjulia.exe import only Windows' DLLs; the DLL exports the C ABI"] = status == 0


# --- consumer ---------------------------------------------------------------------------------


def check_consumer(args, checks):
    dist = require_dist(args)
    version = version_of(args.source)
    # Elsewhere: a folder the build never saw, with a space in its name. (Its files against the
    # build's: release.archive_debian, in clean Debian roots.)
    top = unpack(dist / ("dqjulia-%s-linux-x64.tar.gz" % version), args.work / "consumer" / "unpacked elsewhere")
    status, output = run([top / "bin" / "dqjulia", "--version"])
    checks["the unpacked dqjulia --version: %s" % output.strip()] = status == 0 and version in output
    # A C program of someone else's against the unpacked tree, both ways (tests/consumer).
    consumer = args.source / "tests" / "consumer"
    status, output = run(
        [
            "cmake",
            "-DPREFIX=%s" % top,
            "-DSOURCE=%s" % consumer,
            "-DWORK=%s" % (args.work / "consumer" / "build"),
            "-DCC=%s" % (shutil.which("cc") or "cc"),
            "-P",
            consumer / "consumer_test.cmake",
        ]
    )
    print(output)
    checks["a C program built against the archive by find_package(dqjulia) and pkg-config runs"] = status == 0


# --- windows ----------------------------------------------------------------------------------


def check_windows(args, checks):
    dist = require_dist(args)
    if not args.emulator:
        skip_or_fail("wine64 is not installed (scripts/install-deps.sh installs it)")
    version = version_of(args.source)
    top = unpack(dist / ("dqjulia-%s-windows-x64.zip" % version), args.work / "windows" / "unpacked elsewhere")
    exe = top / "bin" / "dqjulia.exe"
    status, output = run([*args.emulator, exe, "--version"])
    checks["the unpacked dqjulia.exe --version under Wine: %s" % output.strip()] = status == 0 and version in output
    cli_test = args.source / "tests" / "windows" / "cli_test.py"
    cli_work = args.work / "windows" / "cli"
    status, output = run([sys.executable, cli_test, cli_work, args.linux_build, exe, *args.emulator])
    print(output)
    checks["the archive's dqjulia.exe renders, bakes and meshes as Linux does (cli_test.py)"] = status == 0


# --- licenses ---------------------------------------------------------------------------------


def package_platform(name):
    """The platform whose notices a package of the release must carry (None: the sdist)."""
    if "windows" in name or "win_amd64" in name:
        return "windows-x64"
    if "linux" in name:
        return "linux-x64"
    return None


def check_licenses(args, checks):
    dist = require_dist(args)
    builds = {"linux-x64": args.linux_build, "windows-x64": args.windows_build}
    expected = {t: {n: (b / "licenses" / n).read_bytes() for n in NOTICES} for t, b in builds.items()}
    license_text = (args.source / "LICENSE").read_bytes()
    same = all(e["LICENSE"] == license_text for e in expected.values())
    checks["build/licenses/LICENSE is the project's LICENSE"] = same
    packages = sorted(p for p in dist.iterdir() if p.name.endswith((".zip", ".tar.gz", ".whl")))
    for package in packages:
        members = archive_members(package)
        platform = package_platform(package.name)
        if platform is None:  # the sdist: the source, with its LICENSE
            found = [n for n in members if n.count("/") == 1 and n.endswith("/LICENSE")]
            same = bool(found) and members[found[0]][4] == license_text
            checks["%s holds LICENSE (%s)" % (package.name, found)] = same
            continue
        for notice in NOTICES:
            found = [n for n in members if n.rsplit("/", 1)[-1] == notice]
            same = bool(found) and all(members[n][4] == expected[platform][notice] for n in found)
            checks["%s holds %s of %s (%s)" % (package.name, notice, platform, found)] = same
    listing = json.loads((dist / "THIRD-PARTY.json").read_text(encoding="utf-8"))
    data = components(args.source)
    for target in TARGETS:
        names = [c["name"] for c in listing["targets"].get(target, [])]
        wanted = [c["name"] for c in data["components"] if target in c["in"]]
        checks["THIRD-PARTY.json lists the %d components of %s" % (len(wanted), target)] = names == wanted


def require_dist(args):
    dist = args.work / "dist"
    if not (dist / "SHA256SUMS").is_file():
        skip_or_fail("the release's files are missing: the packaging test (release.package) did not run")
    return dist


CHECKS = {
    "components": check_components,
    "package": check_package,
    "contents": check_contents,
    "consumer": check_consumer,
    "windows": check_windows,
    "licenses": check_licenses,
}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("check", choices=sorted(CHECKS))
    parser.add_argument("--source", type=Path, required=True)
    parser.add_argument("--linux-build", type=Path, required=True)
    parser.add_argument("--windows-build", type=Path, required=True)
    parser.add_argument("--work", type=Path, required=True)
    parser.add_argument("--glibc-floor", default="2.34", help="the oldest glibc the Linux binaries run on")
    parser.add_argument("--emulator", nargs=argparse.REMAINDER, default=[])
    args = parser.parse_args()
    for name in ("source", "linux_build", "windows_build", "work"):
        setattr(args, name, getattr(args, name).resolve())
    for build in (args.linux_build, args.windows_build):
        if not (build / "CMakeCache.txt").is_file():
            skip_or_fail("%s is not built (scripts/build.sh, scripts/build-windows.sh)" % build)
    args.work.mkdir(parents=True, exist_ok=True)
    checks = {}
    CHECKS[args.check](args, checks)
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
