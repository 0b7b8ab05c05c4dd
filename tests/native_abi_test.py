"""The add-on's ctypes bindings (blender_addon/dqjulia/native.py) against the C header
(core/include/dqjulia/dqjulia.h): every status code, every function with its argument count,
and the fields of every struct, so the bindings can never drift from the ABI they describe.

Usage: python3 native_abi_test.py SOURCE_DIR
"""

import ctypes
import importlib.util
import re
import sys

CTYPES = {"int32_t": ctypes.c_int32, "double": ctypes.c_double, "uint64_t": ctypes.c_uint64,
          "float": ctypes.c_float, "uint32_t": ctypes.c_uint32, "size_t": ctypes.c_size_t}


def main():
    source = sys.argv[1]
    header = open(source + "/core/include/dqjulia/dqjulia.h").read()
    header = re.sub(r"/\*.*?\*/", "", header, flags=re.S)
    spec = importlib.util.spec_from_file_location("native", source + "/blender_addon/dqjulia/native.py")
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
        arguments = arguments.strip()
        functions[name] = 0 if arguments in ("", "void") else arguments.count(",") + 1
    for name, count in functions.items():
        bound = native._SIGNATURES.get(name)
        checks["function %s(%d arguments)" % (name, count)] = bound is not None and len(bound[1]) == count
    for name in native._SIGNATURES:
        checks["binding %s is in the header" % name] = name in functions

    for struct, cls in (("dqj_sample", native.Sample), ("dqj_bake_stats", native.BakeStats)):
        body = re.search(r"typedef struct %s \{(.*?)\} %s;" % (struct, struct), header, re.S).group(1)
        fields = [(name, CTYPES[kind]) for kind, name in re.findall(r"(\w+)\s+(\w+);", body)]
        checks["struct %s fields" % struct] = fields == list(cls._fields_)

    for name, ok in checks.items():
        if not ok:
            print("FAIL: %s" % name)
    failed = sum(not ok for ok in checks.values())
    print("%d passed, %d failed" % (len(checks) - failed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
