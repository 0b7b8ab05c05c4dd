"""What the standalone test scripts share: their named checks printed and turned into an exit
status, and a missing prerequisite skipped (ctest reads DQJ_TEST_SKIPPED) or, under CI=true,
failed, since CI must run every test."""

import os
import sys


def skip_or_fail(reason):
    if os.environ.get("CI") == "true":
        sys.exit("FAIL: %s (CI=true: every test must run)" % reason)
    print("DQJ_TEST_SKIPPED: %s" % reason)
    sys.exit(0)


def report(checks, failures_only=False):
    """Prints each check ("ok: name", "FAIL: name"; only the failures if failures_only) and the
    totals; the exit status: 1 if any check failed."""
    failed = [name for name, ok in checks.items() if not ok]
    for name, ok in checks.items():
        if not ok or not failures_only:
            print("%s: %s" % ("ok" if ok else "FAIL", name))
    print("%d passed, %d failed" % (len(checks) - len(failed), len(failed)))
    return 1 if failed else 0
