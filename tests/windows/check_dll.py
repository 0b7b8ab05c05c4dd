"""Checks that the Windows build is self-contained, as tests/cleanroom/check_library.py does for
Linux: dqjulia.dll and dqjulia.exe import nothing but Windows' own DLLs and the C runtime
(objdump -p lists them), and the DLL exports exactly the C ABI: the dqj_* functions of dqjulia.h,
so every function the add-on's native.py binds.

Usage: python3 check_dll.py OBJDUMP SOURCE_DIR DQJULIA_DLL DQJULIA_EXE [PROGRAM.exe...]
(the further programs, the test programs, may import dqjulia.dll too)
Prints each file's size and imports, and the DLL's export count.
"""

import os
import re
import subprocess
import sys

# Windows' own DLLs and its C runtime (msvcrt.dll, and the Universal CRT's api-ms-win-crt-*).
SYSTEM_DLLS = {
    "kernel32.dll",
    "msvcrt.dll",
    "advapi32.dll",
    "user32.dll",
    "shell32.dll",
    "ole32.dll",
    "oleaut32.dll",
    "ws2_32.dll",
    "bcrypt.dll",
    "ntdll.dll",
}


def allowed(name, extra):
    name = name.lower()
    return name in SYSTEM_DLLS or name.startswith("api-ms-win-crt-") or name in extra


def main():
    objdump, source, dll, exe, *programs = sys.argv[1:]
    failures = []
    with open(os.path.join(source, "core/include/dqjulia/dqjulia.h")) as file:
        header = re.sub(r"/\*.*?\*/", "", file.read(), flags=re.S)
    functions = set(re.findall(r"DQJ_API\s+[\w\s\*]+?\b(dqj_\w+)\s*\(", header))

    for path in [dll, exe, *programs]:
        dump = subprocess.run([objdump, "-p", path], check=True, capture_output=True, text=True).stdout
        imports = re.findall(r"^\s*DLL Name: (\S+)", dump, re.M)
        name = os.path.basename(path)
        print("%s: %.1f MB, imports %s" % (name, os.path.getsize(path) / 1e6, " ".join(imports)))
        extra = {"dqjulia.dll"} if path in programs else set()
        for imported in imports:
            if not allowed(imported, extra):
                failures.append("%s imports %s, which is not a Windows system DLL nor the C runtime" % (name, imported))
        if path == dll:
            # The export table: "[ordinal] name" lines after "[Ordinal/Name Pointer] Table".
            table = dump.split("[Ordinal/Name Pointer] Table", 1)[-1]
            exports = set(re.findall(r"^\s*\[\s*\d+\]\s+(\S+)\s*$", table, re.M))
            print("%s exports %d functions" % (name, len(exports)))
            for missing in sorted(functions - exports):
                failures.append("%s does not export %s (dqjulia.h)" % (name, missing))
            for stray in sorted(exports - functions)[:20]:
                failures.append("%s exports %s, which is not in the C ABI" % (name, stray))

    for failure in failures:
        print("FAIL: " + failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
