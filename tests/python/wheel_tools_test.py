"""PyPA's own checkers on the wheels and the sdist of DIST: `twine check --strict` (the metadata
and the description PyPI would render) on every file, and `auditwheel show` on each Linux wheel,
which must find it consistent with the platform tag it carries (manylinux_2_34_x86_64: nothing
but glibc 2.34's symbols and the libraries the manylinux policy allows).

Usage: python3 wheel_tools_test.py DIST TWINE AUDITWHEEL   (the tools of scripts/tool-env.sh)
"""

import glob
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report, skip_or_fail  # noqa: E402 (tests/common/check_report.py)


def main():
    dist, twine, auditwheel = sys.argv[1:4]
    for tool in (twine, auditwheel):
        if not os.access(tool, os.X_OK):
            skip_or_fail("%s is not installed (scripts/tool-env.sh %s installs it)" % (tool, os.path.basename(tool)))
    files = sorted(glob.glob(os.path.join(dist, "*.whl")) + glob.glob(os.path.join(dist, "*.tar.gz")))
    checks = {"%s holds wheels and an sdist (%d files)" % (dist, len(files)): len(files) >= 2}
    for path in files:
        result = subprocess.run([twine, "check", "--strict", path], capture_output=True, text=True)
        output = re.sub(r"\x1b\[[0-9;]*m", "", result.stdout + result.stderr).strip()
        print(output)
        checks["twine check --strict %s: %s" % (os.path.basename(path), output.splitlines()[-1:])] = (
            result.returncode == 0 and "PASSED" in output
        )
    for path in files:
        tag = re.search(r"-py3-none-(manylinux_\w+)\.whl$", path)
        if tag is None:
            continue
        result = subprocess.run([auditwheel, "show", path], capture_output=True, text=True)
        output = " ".join((result.stdout + result.stderr).split())
        print(output)
        checks["auditwheel show: %s is consistent with its tag %s" % (os.path.basename(path), tag.group(1))] = (
            result.returncode == 0 and 'is consistent with the following platform tag: "%s"' % tag.group(1) in output
        )
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
