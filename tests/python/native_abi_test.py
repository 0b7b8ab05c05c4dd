"""The ctypes bindings (python/dqjulia/_native.py: the Python package's, and the add-on's native.py,
a copy) against the C header
(core/include/dqjulia/dqjulia.h): every status code, feature name and function with its
argument count, the fields of every struct, and the progress callback's convention, so the
bindings can never drift from the ABI they describe. Given the C test program, also each
struct's size and each field's offset and size as the C compiler lays them out
(`c_api_test --layout`) against ctypes'.

Usage: python3 tests/python/native_abi_test.py SOURCE_DIR [C_API_TEST]
       python3 tests/python/native_abi_test.py SOURCE_DIR EMULATOR... C_API_TEST   (a Windows build's, under Wine)
"""

import ctypes
import importlib.util
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report  # noqa: E402 (tests/common/check_report.py)

CTYPES = {
    "int32_t": ctypes.c_int32,
    "double": ctypes.c_double,
    "uint64_t": ctypes.c_uint64,
    "float": ctypes.c_float,
    "uint32_t": ctypes.c_uint32,
    "size_t": ctypes.c_size_t,
}


def main():
    source = sys.argv[1]
    with open(source + "/core/include/dqjulia/dqjulia.h") as file:
        header = file.read()
    header = re.sub(r"/\*.*?\*/", "", header, flags=re.S)
    spec = importlib.util.spec_from_file_location("native", source + "/python/dqjulia/_native.py")
    native = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(native)
    checks = {}

    statuses = dict(re.findall(r"\bDQJ_(OK|ERROR_[A-Z_]+)\s*=\s*(\d+)", header))
    for name, value in statuses.items():
        checks["status %s = %s" % (name, value)] = getattr(native, name, None) == int(value)

    variants = re.findall(r"\bDQJ_VARIANT_([A-Z_]+)\s*=\s*(\d+)", header)
    checks["variants %s" % [name for name, _ in variants]] = [
        name.lower().replace("_", "-") for name, _ in sorted(variants, key=lambda item: int(item[1]))
    ] == list(native.VARIANTS)

    functions = {}
    for name, arguments in re.findall(r"DQJ_API\s+[\w\s\*]+?\b(dqj_\w+)\s*\(([^)]*)\)", header):
        listed = arguments.strip()
        functions[name] = 0 if listed in ("", "void") else listed.count(",") + 1
    for name, count in functions.items():
        bound = native._SIGNATURES.get(name)
        checks["function %s(%d arguments)" % (name, count)] = bound is not None and len(bound[1]) == count
    for name, (_restype, _argtypes, features) in native._SIGNATURES.items():
        checks["binding %s is in the header" % name] = name in functions
        checks["binding %s needs known features %s" % (name, features)] = features is None or (
            len(features) > 0 and set(features) <= set(native.FEATURES)
        )

    features = dict(re.findall(r"#define\s+DQJ_FEATURE_(\w+)\s+\"(\w+)\"", header))
    checks["features %s" % sorted(features.values())] = sorted(features.values()) == sorted(native.FEATURES)
    for name, value in features.items():
        checks["feature %s = %r" % (name, value)] = getattr(native, "FEATURE_" + name, None) == value

    groups = dict(re.findall(r"#define\s+DQJ_GROUP_(\w+)\s+(0x[0-9a-f]+)u", header))
    for name, value in groups.items():
        checks["group %s = %s" % (name, value)] = getattr(native, "GROUP_" + name, None) == int(value, 16)
    strengths = dict(re.findall(r"#define\s+DQJ_STRENGTH_(\w+)\s+([0-9.]+)", header))
    checks["strengths %s" % strengths] = {k.lower(): float(v) for k, v in strengths.items()} == native.STRENGTHS

    structs = (("dqj_sample", native.Sample), ("dqj_bake_stats", native.BakeStats))
    for struct, cls in structs:
        body = re.search(r"typedef struct %s \{(.*?)\} %s;" % (struct, struct), header, re.S).group(1)
        fields = [(name, CTYPES[kind]) for kind, name in re.findall(r"(\w+)\s+(\w+);", body)]
        checks["struct %s fields" % struct] = fields == list(cls._fields_)
    # Growing structs start with struct_size (dqjulia.h); the frozen one (an array element) does not.
    checks["dqj_bake_stats starts with struct_size"] = native.BakeStats._fields_[0] == ("struct_size", ctypes.c_size_t)
    checks["DQJ_BAKE_STATS_INIT sets struct_size"] = (
        re.search(r"#define\s+DQJ_BAKE_STATS_INIT[\s\\]+\{\s*\.struct_size = sizeof\(dqj_bake_stats\)\s*\}", header)
        is not None
    )

    # dqj_progress_fn: non-zero goes on, 0 cancels.
    progress = native.Progress()
    checks["progress goes on with non-zero"] = progress._report(0.5, None) != 0
    progress.cancel()
    checks["progress cancels with 0"] = progress._report(0.6, None) == 0

    if len(sys.argv) > 2:
        # Lines "STRUCT SIZE" and "STRUCT.FIELD OFFSET SIZE".
        layout = subprocess.run(sys.argv[2:] + ["--layout"], check=True, capture_output=True, text=True).stdout
        sizes = {}
        for line in layout.splitlines():
            name, *numbers = line.split()
            sizes[name] = [int(number) for number in numbers]
        for struct, cls in structs:
            size = sizes.get(struct)
            checks["sizeof(%s) = %s, ctypes %d" % (struct, size, ctypes.sizeof(cls))] = size == [ctypes.sizeof(cls)]
            for field, kind in cls._fields_:
                expected = [getattr(cls, field).offset, ctypes.sizeof(kind)]
                found = sizes.get("%s.%s" % (struct, field))
                checks["%s.%s at %s in C, %s in ctypes" % (struct, field, found, expected)] = found == expected

    return report(checks, failures_only=True)


if __name__ == "__main__":
    sys.exit(main())
