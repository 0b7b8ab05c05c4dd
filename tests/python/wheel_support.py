"""What the Python package's tests share: reading a wheel (its tags, metadata, RECORD) as an
installer does, the 8-bit PNGs and binary PLY meshes the command writes, and finding a CPython."""

import base64
import csv
import glob
import hashlib
import io
import os
import re
import shutil
import struct
import subprocess
import zipfile
import zlib

EXPECTED_FILES = {  # the package's files in a wheel, by wheel platform
    "manylinux_2_34_x86_64": {"dqjulia/lib/libdqjulia.so", "dqjulia/bin/dqjulia"},
    "win_amd64": {"dqjulia/lib/dqjulia.dll", "dqjulia/bin/dqjulia.exe"},
}
MODULES = {
    "dqjulia/__init__.py",
    "dqjulia/__main__.py",
    "dqjulia/_buildinfo.py",
    "dqjulia/_cli.py",
    "dqjulia/_fractal.py",
    "dqjulia/_native.py",
    "dqjulia/py.typed",
}


def check_wheel(path, source, version, platform, epoch=None):
    """The checks of a wheel's contents, as an installer reads them: its name and tag, WHEEL,
    METADATA, entry point, licences, RECORD (every file with its SHA-256 and size, nothing else),
    the files of the package, the executable's mode, the bindings equal to the source's, and
    reproducible entries (sorted, time SOURCE_DATE_EPOCH). Returns {name: ok}."""
    checks = {}
    name = os.path.basename(path)
    tag = "py3-none-%s" % platform
    checks["the wheel is named %s" % name] = name == "dqjulia-%s-%s.whl" % (version, tag)
    info = "dqjulia-%s.dist-info" % version
    with zipfile.ZipFile(path) as archive:
        entries = archive.infolist()
        names = [entry.filename for entry in entries]
        read = {entry: archive.read(entry) for entry in names}
    wheel = read.get(info + "/WHEEL", b"").decode()
    checks["WHEEL: Root-Is-Purelib false, the one tag %s" % tag] = "Root-Is-Purelib: false" in wheel and re.findall(
        r"^Tag: (.*)$", wheel, re.M
    ) == [tag]
    metadata = read.get(info + "/METADATA", b"").decode()
    fields = re.findall(r"^([A-Za-z-]+): (.*)$", metadata.split("\n\n", 1)[0], re.M)
    values = {}
    for key, value in fields:
        values.setdefault(key, []).append(value)
    checks["METADATA: Name dqjulia, Version %s" % version] = values.get("Name") == ["dqjulia"] and values.get(
        "Version"
    ) == [version]
    checks["METADATA: Requires-Python >=3.9, License-Expression GPL-3.0-or-later"] = values.get("Requires-Python") == [
        ">=3.9"
    ] and values.get("License-Expression") == ["GPL-3.0-or-later"]
    checks["METADATA: NumPy an extra, no other requirement"] = values.get("Requires-Dist") == [
        'numpy>=1.21; extra == "numpy"'
    ]
    license_files = values.get("License-File", [])
    checks["each License-File is in the wheel (%s)" % ", ".join(license_files)] = "LICENSE" in license_files and all(
        "%s/licenses/%s" % (info, file) in names for file in license_files
    )
    checks["the description is the package README"] = "# dqjulia" in metadata.split("\n\n", 1)[-1]
    entry_points = read.get(info + "/entry_points.txt", b"").decode()
    checks["entry point: dqjulia = dqjulia._cli:main"] = (
        entry_points == "[console_scripts]\ndqjulia = dqjulia._cli:main\n"
    )

    record = list(csv.reader(io.StringIO(read.get(info + "/RECORD", b"").decode())))
    recorded = {row[0]: row[1:] for row in record}
    checks["RECORD lists every file once, itself last"] = (
        sorted(recorded) == sorted(names) and len(record) == len(names) and record[-1] == [info + "/RECORD", "", ""]
    )
    wrong = [
        entry
        for entry in names
        if entry != info + "/RECORD"
        and recorded.get(entry)
        != [
            "sha256=" + base64.urlsafe_b64encode(hashlib.sha256(read[entry]).digest()).rstrip(b"=").decode(),
            str(len(read[entry])),
        ]
    ]
    checks["RECORD's hashes and sizes are the files' (wrong: %s)" % wrong] = not wrong

    package = {entry for entry in names if not entry.startswith(info + "/")}
    expected = MODULES | EXPECTED_FILES[platform]
    checks["the package holds exactly %s" % sorted(expected)] = package == expected
    command = [entry for entry in entries if entry.filename.startswith("dqjulia/bin/")]
    checks["the command's mode is 0755"] = bool(command) and all(
        (entry.external_attr >> 16) & 0o777 == 0o755 for entry in command
    )
    with open(os.path.join(source, "python", "dqjulia", "_native.py"), "rb") as file:
        checks["the wheel's _native.py is python/dqjulia/_native.py"] = read.get("dqjulia/_native.py") == file.read()
    checks["entries sorted, dist-info last"] = names == sorted(package) + [
        entry for entry in names if entry.startswith(info + "/")
    ]
    if epoch is not None:
        import time

        # A zip entry's time has a resolution of two seconds (MS-DOS time): an odd second is stored
        # as the even one before it.
        stamp = time.gmtime(max(epoch, 315532800) // 2 * 2)[:6]
        checks["every entry's time is SOURCE_DATE_EPOCH %d (to the zip's 2 s)" % epoch] = all(
            entry.date_time == stamp for entry in entries
        )
    return checks


def read_png(path):
    """(width, height, channels, rows as bytes) of a non-interlaced 8-bit PNG."""
    with open(path, "rb") as file:
        data = file.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("%s is not a PNG" % path)
    position, idat = 8, b""
    while position < len(data):
        length, kind = struct.unpack(">I4s", data[position : position + 8])
        body = data[position + 8 : position + 8 + length]
        position += 12 + length
        if kind == b"IHDR":
            width, height, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
    if depth != 8 or interlace != 0 or color not in (0, 2, 4, 6):
        raise ValueError("%s: only non-interlaced 8-bit PNGs are read here" % path)
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[color]
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous, position = [], bytearray(stride), 0
    for _ in range(height):
        kind, line = raw[position], bytearray(raw[position + 1 : position + 1 + stride])
        position += 1 + stride
        for index in range(stride):
            left = line[index - channels] if index >= channels else 0
            up = previous[index]
            corner = previous[index - channels] if index >= channels else 0
            if kind == 1:
                line[index] = (line[index] + left) & 255
            elif kind == 2:
                line[index] = (line[index] + up) & 255
            elif kind == 3:
                line[index] = (line[index] + (left + up) // 2) & 255
            elif kind == 4:
                estimate = left + up - corner
                distances = (abs(estimate - left), abs(estimate - up), abs(estimate - corner))
                predictor = (
                    left if distances[0] <= min(distances[1:]) else up if distances[1] <= distances[2] else corner
                )
                line[index] = (line[index] + predictor) & 255
        rows.append(bytes(line))
        previous = line
    return width, height, channels, b"".join(rows)


def read_ply(path):
    """The vertices of a binary PLY the command writes, as (float x y z nx ny nz per vertex, in one
    bytes), and its faces as lists of indices."""
    with open(path, "rb") as file:
        data = file.read()
    header_end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:header_end].decode()
    vertices = int(re.search(r"element vertex (\d+)", header).group(1))
    faces = int(re.search(r"element face (\d+)", header).group(1))
    properties = re.findall(r"property (float|uchar) (\w+)", header.split("element face")[0])
    layout = "<" + "".join("f" if kind == "float" else "B" for kind, _ in properties)
    size = struct.calcsize(layout)
    floats, colors, position = [], [], header_end
    for _ in range(vertices):
        values = struct.unpack_from(layout, data, position)
        position += size
        floats.append(struct.pack("<6f", *values[:6]))
        colors.append(values[6:])
    face_list = []
    for _ in range(faces):
        count = data[position]
        face_list.append(list(struct.unpack_from("<%dI" % count, data, position + 1)))
        position += 1 + 4 * count
    return b"".join(floats), colors, face_list


def find_python(version):
    """The interpreter of a CPython: 'debian' is Debian's /usr/bin/python3; '3.X' is pyenv's newest
    3.X (`pyenv root`, or ~/.pyenv), else python3.X on PATH. None if this machine has none."""
    if version == "debian":
        return "/usr/bin/python3" if os.access("/usr/bin/python3", os.X_OK) else None
    roots = []
    if shutil.which("pyenv"):
        result = subprocess.run(["pyenv", "root"], capture_output=True, text=True)
        if result.returncode == 0 and result.stdout.strip():
            roots.append(result.stdout.strip())
    roots.append(os.environ.get("PYENV_ROOT") or os.path.expanduser("~/.pyenv"))
    for root in roots:
        found = glob.glob(os.path.join(root, "versions", version + ".*", "bin", "python3"))
        found = [path for path in found if re.search(r"/%s\.\d+/bin/" % re.escape(version), path)]
        if found:
            return max(found, key=lambda path: int(re.search(r"\.(\d+)/bin/", path).group(1)))
    return shutil.which("python" + version)
