#!/usr/bin/env python3
"""Shows where two release folders (scripts/dist.py's) differ, down to the files inside their
archives, as diffoscope would: files only in one, entries only in one, entries whose order, time,
mode or owner differ, and for a differing entry the first differing byte, the differing lines of
a text or the differing strings of a binary. With --forbid, also every file or entry holding one
of the given strings (the paths of the two clones: a release must name neither).

Usage: dist-diff.py FOLDER_A FOLDER_B [--forbid STRING]...
Exit status 0 when the folders hold the same bytes and no forbidden string.
"""

import argparse
import difflib
import io
import re
import sys
import tarfile
import zipfile
from pathlib import Path

LIMIT = 12  # differences shown per file


def members(name, data):
    """[(entry name, metadata, bytes)] of an archive in its order, or None if it is none."""
    if name.endswith((".zip", ".whl")):
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            return [
                (i.filename, (i.date_time, i.external_attr, i.create_system, i.compress_type), archive.read(i))
                for i in archive.infolist()
            ]
    if name.endswith(".tar.gz"):
        with tarfile.open(fileobj=io.BytesIO(data)) as archive:
            found = []
            for i in archive.getmembers():
                contents = archive.extractfile(i).read() if i.isfile() else i.linkname.encode()
                found.append((i.name, (i.mtime, i.mode, i.uid, i.gid, i.uname, i.gname, i.type), contents))
            return found
    return None


def strings(data):
    return set(re.findall(rb"[\x20-\x7e]{6,}", data))


def describe(name, a, b):
    """Lines saying how two versions of one file's bytes differ."""
    lines = []
    offset = next((i for i, (x, y) in enumerate(zip(a, b)) if x != y), min(len(a), len(b)))
    lines.append("%s: %d and %d bytes, first difference at byte %d" % (name, len(a), len(b), offset))
    try:
        text_a, text_b = a.decode("utf-8"), b.decode("utf-8")
    except UnicodeDecodeError:
        only_a, only_b = strings(a) - strings(b), strings(b) - strings(a)
        lines += ["  - %r" % s for s in sorted(only_a)[:LIMIT]]
        lines += ["  + %r" % s for s in sorted(only_b)[:LIMIT]]
        return lines
    diff = difflib.unified_diff(text_a.splitlines(), text_b.splitlines(), lineterm="", n=1)
    lines += ["  " + line for line in list(diff)[2 : 2 + 4 * LIMIT]]
    return lines


def compare(name, a, b):
    inner_a, inner_b = members(name, a), members(name, b)
    if inner_a is None or inner_b is None:
        return describe(name, a, b)
    lines = []
    names_a, names_b = [m[0] for m in inner_a], [m[0] for m in inner_b]
    for entry in sorted(set(names_a) - set(names_b))[:LIMIT]:
        lines.append("%s: only in the first: %s" % (name, entry))
    for entry in sorted(set(names_b) - set(names_a))[:LIMIT]:
        lines.append("%s: only in the second: %s" % (name, entry))
    if [n for n in names_a if n in names_b] != [n for n in names_b if n in names_a]:
        lines.append("%s: the entries are in another order" % name)
    by_name_b = {m[0]: m for m in inner_b}
    for entry, meta, data in inner_a:
        if entry not in by_name_b:
            continue
        _, other_meta, other_data = by_name_b[entry]
        if meta != other_meta:
            lines.append("%s: %s: metadata %s and %s" % (name, entry, meta, other_meta))
        if data != other_data:
            lines += describe("%s: %s" % (name, entry), data, other_data)
    return lines or ["%s: differs, but not in its entries (the archive's own bytes)" % name]


def forbidden_in(name, data, forbid):
    hits = [text for text in forbid if text.encode() in data]
    found = ["%s holds %s" % (name, text) for text in hits]
    for entry, _, contents in members(name, data) or []:
        found += ["%s: %s holds %s" % (name, entry, text) for text in forbid if text.encode() in contents]
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("first", type=Path)
    parser.add_argument("second", type=Path)
    parser.add_argument("--forbid", action="append", default=[], help="a string no file may hold")
    args = parser.parse_args()
    names_a = {p.name for p in args.first.iterdir() if p.is_file()}
    names_b = {p.name for p in args.second.iterdir() if p.is_file()}
    report = ["only in %s: %s" % (args.first, n) for n in sorted(names_a - names_b)]
    report += ["only in %s: %s" % (args.second, n) for n in sorted(names_b - names_a)]
    for name in sorted(names_a | names_b):
        data = {}
        for folder in (args.first, args.second):
            if (folder / name).is_file():
                data[folder] = (folder / name).read_bytes()
                report += forbidden_in(str(folder / name), data[folder], args.forbid)
        if len(data) == 2 and data[args.first] != data[args.second]:
            report += compare(name, data[args.first], data[args.second])
    for line in report:
        print(line)
    print("the same bytes, no forbidden string" if not report else "%d differences" % len(report))
    return 1 if report else 0


if __name__ == "__main__":
    sys.exit(main())
