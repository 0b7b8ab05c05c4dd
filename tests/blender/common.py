"""Helpers shared by the Blender tests, run inside Blender (blender ... --python test.py -- args)
or in a bpy wheel's Python (VENV/bin/python test.py -- args; scripts/bpy-env.sh).

The tests install the add-on from the zip the build made, exactly as a user would (an extension
in 4.2+, a legacy add-on before), into the user folders the test runner points BLENDER_USER_*
at (never the real user's).
"""

import argparse
import os
import sys
import time

import bpy


def bpy_wheel_python_modules():
    """The bpy wheels 4.5 and later ship Blender's own Python modules (oslquery, OpenImageIO, ...)
    in bpy/<version>/python/lib/python3.X/site-packages, which is not on sys.path of the venv's
    Python; Cycles imports oslquery to compile an OSL Script node (4.5+). Blender the program has
    that folder on its path: put it on ours too, so a Script node compiles as it does there."""
    try:
        import oslquery  # noqa: F401

        return
    except ImportError:
        pass
    folder = os.path.join(
        bpy.utils.resource_path("LOCAL"), "python", "lib", "python%d.%d" % sys.version_info[:2], "site-packages"
    )
    if os.path.isdir(folder) and folder not in sys.path:
        sys.path.append(folder)


def arguments(extra=None):
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--zip", required=True, help="build/dist/dqjulia_blender.zip")
    parser.add_argument("--work", required=True, help="a scratch folder (emptied first)")
    parser.add_argument("--examples", default="", help="the examples/ folder")
    parser.add_argument("--cli", default="", help="the dqjulia command, if built")
    if extra:
        extra(parser)
    args = parser.parse_args(argv)
    if blender_kind() == "bpy module":
        bpy_wheel_python_modules()
    if os.path.isdir(args.work):
        import shutil

        shutil.rmtree(args.work)
    os.makedirs(args.work)
    return args


def blender_kind():
    """ "bpy module" (a bpy wheel in a Python) or "blender" (the program running a script)."""
    return "bpy module" if not os.path.basename(bpy.app.binary_path or "").startswith("blender") else "blender"


def uses_extensions():
    """Blender 4.2+ installs the zip as an extension (its blender_manifest.toml); 3.4 - 4.1 as
    a legacy add-on (bl_info)."""
    return bpy.app.version >= (4, 2, 0)


def install_extension(zip_path):
    """Edit > Preferences > Get Extensions > Install from Disk, as a script: into the user
    repository "user_default" (under BLENDER_USER_EXTENSIONS or BLENDER_USER_RESOURCES),
    enabled on install. Returns the add-on's module name (bl_ext.user_default.dqjulia)."""
    import addon_utils

    repos = bpy.context.preferences.extensions.repos
    repo = next((r for r in repos if r.module == "user_default"), None)
    check(repo is not None, "the user repository user_default exists (%s)" % [r.module for r in repos])
    if "package_install_files" not in dir(bpy.ops.extensions):  # bl_pkg off (it is on by default)
        addon_utils.enable("bl_pkg", default_set=True)
    result = bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default", enable_on_install=True)
    check(result == {"FINISHED"}, "extensions.package_install_files returned %s" % result)
    return "bl_ext.user_default.dqjulia"


def install_addon(zip_path, cache_dir):
    """Installs and enables the add-on from the zip (an extension in 4.2+, else addon_install
    + addon_enable); returns the imported package. Its module name is package.__name__."""
    import importlib

    if uses_extensions():
        module = install_extension(zip_path)
        root = bpy.utils.user_resource("EXTENSIONS")
    else:
        result = bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
        check(result == {"FINISHED"}, "addon_install returned %s" % result)
        module = "dqjulia"
        result = bpy.ops.preferences.addon_enable(module=module)
        check(result == {"FINISHED"}, "addon_enable returned %s" % result)
        root = bpy.utils.user_resource("SCRIPTS")
    check(module in bpy.context.preferences.addons, "%s is enabled" % module)
    package = importlib.import_module(module)
    installed = os.path.dirname(package.__file__)
    check(installed.startswith(root), "the add-on runs from %s (under %s)" % (installed, root))
    prefs = bpy.context.preferences.addons[module].preferences
    prefs.cache_dir = cache_dir
    report("installed %s from %s into %s" % (module, os.path.basename(zip_path), installed))
    return package


def submodule(package, name):
    import importlib

    return importlib.import_module(package.__name__ + "." + name)


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
