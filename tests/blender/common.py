"""Helpers shared by the Blender tests (run inside Blender: blender ... --python test.py -- args).

The tests install the add-on from the zip the build made, exactly as a user would, into the
user folders the test runner points BLENDER_USER_* at (never the real user's).
"""

import argparse
import os
import sys
import time

import bpy


def arguments(extra=None):
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--zip", required=True, help="build/dist/dqjulia_blender.zip")
    parser.add_argument("--work", required=True, help="a scratch folder (emptied first)")
    parser.add_argument("--examples", default="", help="the examples/ folder")
    parser.add_argument("--cli", default="", help="the dqjulia command, if built")
    if extra:
        extra(parser)
    args = parser.parse_args(argv)
    if os.path.isdir(args.work):
        import shutil
        shutil.rmtree(args.work)
    os.makedirs(args.work)
    return args


def install_addon(zip_path, cache_dir):
    """addon_install + addon_enable from the zip; returns the imported package."""
    result = bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
    check(result == {"FINISHED"}, "addon_install returned %s" % result)
    result = bpy.ops.preferences.addon_enable(module="dqjulia")
    check(result == {"FINISHED"}, "addon_enable returned %s" % result)
    import dqjulia
    installed = os.path.dirname(dqjulia.__file__)
    check(installed.startswith(bpy.utils.user_resource("SCRIPTS")), "the add-on runs from %s" % installed)
    prefs = bpy.context.preferences.addons["dqjulia"].preferences
    prefs.cache_dir = cache_dir
    report("installed from %s into %s" % (os.path.basename(zip_path), installed))
    return dqjulia


_failures = []
_started = time.monotonic()


def report(message):
    print("[dqjulia test %6.1fs] %s" % (time.monotonic() - _started, message), flush=True)


def check(condition, message):
    if condition:
        report("ok   " + message)
    else:
        report("FAIL " + message)
        _failures.append(message)
    return condition


def failures():
    return list(_failures)


def finish():
    """Raise (so --python-exit-code makes Blender exit non-zero) if any check failed."""
    if _failures:
        raise SystemExit("%d check(s) failed:\n  %s" % (len(_failures), "\n  ".join(_failures)))
    report("all checks passed")


def call(operator, **properties):
    """Runs an operator; returns (result, error text). bpy.ops raises RuntimeError when an
    operator reports an error: that is an expected outcome in these tests, not a crash."""
    try:
        return operator(**properties), ""
    except RuntimeError as error:
        return {"CANCELLED"}, str(error).strip().splitlines()[-1]


def iou(mask_a, mask_b):
    both = sum(1 for a, b in zip(mask_a, mask_b) if a and b)
    either = sum(1 for a, b in zip(mask_a, mask_b) if a or b)
    return 1.0 if either == 0 else both / either
