#!/usr/bin/env python3
"""Packs a folder into a zip or a .tar.gz that is byte-for-byte the same wherever and whenever it
is made from the same files: entries in sorted order, every time stamp SOURCE_DATE_EPOCH (or
--mtime; 1980-01-01 when neither is given), owner and group 0 (root), modes 0755 for folders and
executables and 0644 for other files, no user or host names, gzip without a name or time.

  pack.py zip|tar.gz OUTPUT FOLDER

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


def entries(folder):
    """(archive name, path) of the folder and everything in it, in sorted order of name."""
    found = [(folder.name, folder)]
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            path = Path(root) / name
            found.append((path.relative_to(folder.parent).as_posix(), path))
    return sorted(found)


def mode_of(path):
    info = path.lstat()
    if stat.S_ISDIR(info.st_mode) or info.st_mode & 0o111:
        return 0o755
    return 0o644


def write_zip(output, folder, mtime):
    stamp = time.gmtime(max(mtime, ZIP_EPOCH))[:6]
    with zipfile.ZipFile(output, "w") as archive:
        for name, path in entries(folder):
            if path.is_symlink():
                raise SystemExit("pack.py: %s is a symbolic link, which a zip cannot hold" % path)
            directory = path.is_dir()
            info = zipfile.ZipInfo(name + "/" if directory else name, stamp)
            info.create_system = 3  # Unix, so that the modes are read
            if directory:
                info.external_attr = (stat.S_IFDIR | 0o755) << 16 | 0x10  # and MS-DOS's directory flag
                archive.writestr(info, b"")
            else:
                info.external_attr = (stat.S_IFREG | mode_of(path)) << 16
                info.compress_type = zipfile.ZIP_DEFLATED
                archive.writestr(info, path.read_bytes(), compresslevel=9)


def write_tar_gz(output, folder, mtime):
    data = io.BytesIO()
    with tarfile.open(fileobj=data, mode="w", format=tarfile.PAX_FORMAT) as archive:
        for name, path in entries(folder):
            info = archive.gettarinfo(str(path), arcname=name)
            info.uid = info.gid = 0
            info.uname = info.gname = "root"
            info.mtime = mtime
            if not info.issym():
                info.mode = mode_of(path)
            if info.isreg():
                with path.open("rb") as contents:
                    archive.addfile(info, contents)
            else:
                archive.addfile(info)
    with output.open("wb") as raw, gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=0, compresslevel=9) as out:
        out.write(data.getvalue())


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
    mtime = args.mtime
    if mtime is None:
        mtime = int(os.environ.get("SOURCE_DATE_EPOCH") or ZIP_EPOCH)
    temporary = args.output.with_name(args.output.name + ".tmp")
    try:
        (write_zip if args.format == "zip" else write_tar_gz)(temporary, folder, mtime)
        os.replace(temporary, args.output)
    finally:
        temporary.unlink(missing_ok=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
