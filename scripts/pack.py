#!/usr/bin/env python3
"""Writes zips and .tar.gz files that are byte-for-byte the same wherever and whenever they are
made from the same files: entries in the order given (a folder's: sorted), every time stamp
SOURCE_DATE_EPOCH (or --mtime; 1980-01-01 when neither is given), owner and group 0 (root), modes
0755 for folders and executables and 0644 for other files, no user or host names, gzip without a
name or time. The one writer of the project's archives: the extension zips (the build), the
release's archives (scripts/dist.py), the wheels and the sdist (scripts/build-wheels.py, which
imports it).

  pack.py zip|tar.gz OUTPUT FOLDER [--mtime SECONDS]

The archive holds FOLDER itself (its name as the top entry) and everything in it; symbolic links
are kept as links in a .tar.gz and refused in a zip. OUTPUT is written aside and renamed into
place, so it is whole or absent.
"""

import argparse
import gzip
import io
import os
import stat
import sys
import tarfile
import time
import zipfile
from pathlib import Path

ZIP_EPOCH = 315532800  # 1980-01-01T00:00:00Z: the earliest time a zip entry can hold


class PackError(Exception):
    pass


class Link:
    """A symbolic link's target, as a member's contents (a .tar.gz only)."""

    def __init__(self, target):
        self.target = target


def mode_of(path):
    info = path.lstat()
    if stat.S_ISDIR(info.st_mode) or info.st_mode & 0o111:
        return 0o755
    return 0o644


def folder_members(folder):
    """(name, contents, mode) of FOLDER (its name as the top entry) and everything in it, sorted by
    name; contents: the bytes of a file, None for a folder, a Link for a symbolic link."""
    found = [(folder.name, folder)]
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            path = Path(root) / name
            found.append((path.relative_to(folder.parent).as_posix(), path))
    members = []
    for name, path in sorted(found):
        if path.is_symlink():
            members.append((name, Link(os.readlink(path)), 0o777))
        elif path.is_dir():
            members.append((name, None, 0o755))
        else:
            members.append((name, path.read_bytes(), mode_of(path)))
    return members


def write_aside(output, write):
    """Calls write(temporary path), then renames the temporary file to OUTPUT."""
    output = Path(output)
    temporary = output.with_name("." + output.name + ".tmp")
    try:
        write(temporary)
        os.replace(temporary, output)
    finally:
        temporary.unlink(missing_ok=True)


def write_zip(output, members, mtime):
    """A zip of members (name, contents, mode) in their order; deflated, Unix modes."""
    stamp = time.gmtime(max(mtime, ZIP_EPOCH))[:6]

    def write(path):
        with zipfile.ZipFile(path, "w") as archive:
            for name, contents, mode in members:
                if isinstance(contents, Link):
                    raise PackError("%s is a symbolic link, which a zip cannot hold" % name)
                info = zipfile.ZipInfo(name + "/" if contents is None else name, stamp)
                info.create_system = 3  # Unix, so that the modes are read
                if contents is None:
                    info.external_attr = (stat.S_IFDIR | mode) << 16 | 0x10  # and MS-DOS's directory flag
                    archive.writestr(info, b"")
                else:
                    info.external_attr = (stat.S_IFREG | mode) << 16
                    info.compress_type = zipfile.ZIP_DEFLATED
                    archive.writestr(info, contents, compresslevel=9)

    write_aside(output, write)


def write_tar_gz(output, members, mtime):
    """A POSIX (pax) tar of members (name, contents, mode) in their order, owned by root, gzipped."""
    data = io.BytesIO()
    with tarfile.open(fileobj=data, mode="w", format=tarfile.PAX_FORMAT) as archive:
        for name, contents, mode in members:
            info = tarfile.TarInfo(name)
            info.mtime = mtime
            info.mode = mode
            info.uid = info.gid = 0
            info.uname = info.gname = "root"
            if contents is None:
                info.type = tarfile.DIRTYPE
                archive.addfile(info)
            elif isinstance(contents, Link):
                info.type = tarfile.SYMTYPE
                info.linkname = contents.target
                archive.addfile(info)
            else:
                info.size = len(contents)
                archive.addfile(info, io.BytesIO(contents))

    def write(path):
        with (
            path.open("wb") as raw,
            gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=0, compresslevel=9) as out,
        ):
            out.write(data.getvalue())

    write_aside(output, write)


def source_date_epoch(default=ZIP_EPOCH):
    value = os.environ.get("SOURCE_DATE_EPOCH")
    if not value:
        return default
    if not value.isdigit():
        raise PackError("SOURCE_DATE_EPOCH must be a number of seconds, not %r" % value)
    return int(value)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("format", choices=["zip", "tar.gz"])
    parser.add_argument("output", type=Path)
    parser.add_argument("folder", type=Path)
    parser.add_argument("--mtime", type=int, help="entries' time (seconds since 1970); default SOURCE_DATE_EPOCH")
    args = parser.parse_args()
    folder = args.folder.resolve()
    if not folder.is_dir():
        raise SystemExit("pack.py: %s is not a folder" % args.folder)
    try:
        mtime = source_date_epoch() if args.mtime is None else args.mtime
        (write_zip if args.format == "zip" else write_tar_gz)(args.output, folder_members(folder), mtime)
    except (PackError, OSError) as error:
        raise SystemExit("pack.py: %s" % error) from None
    return 0


if __name__ == "__main__":
    sys.exit(main())
