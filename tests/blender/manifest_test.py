"""Strict validation of the add-on zip as an extension, in a Blender 4.2+ (bpy wheel):

  VENV/bin/python tests/blender/manifest_test.py --zip build/dist/dqjulia_blender.zip --work DIR

Runs what `blender --command extension validate ZIP` runs: the core add-on bl_pkg's command
line handler (bl_pkg.bl_extension_cli, with Blender's own list of valid tags), which parses
blender_manifest.toml with strict=True (field lengths, tags, licence, platforms, permissions)
and checks the add-on's __init__.py is in the archive. A broken copy of the manifest must fail
the same validation, so the test cannot pass by validating nothing.
"""

import os
import sys
import tomllib
import zipfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402
from common import check, report  # noqa: E402

ARGS = common.arguments()
check(bpy.app.version >= (4, 2, 0), "Blender %s has extensions (4.2+)" % bpy.app.version_string)
from bl_pkg import bl_extension_cli  # noqa: E402  (a core add-on: scripts/addons_core/bl_pkg)


def validate(path):
    report("blender --command extension validate %s" % os.path.basename(path))
    return bl_extension_cli.cli_extension_handler(["validate", path])


check(validate(ARGS.zip) == 0, "the add-on zip passes strict validation")

with zipfile.ZipFile(ARGS.zip) as archive:
    manifest_name = next(name for name in archive.namelist() if name.endswith("blender_manifest.toml"))
    manifest = tomllib.loads(archive.read(manifest_name).decode("utf-8"))
    check(manifest_name == "dqjulia/blender_manifest.toml", "the manifest is %s" % manifest_name)
    check(manifest["platforms"] == ["linux-x64"], "platforms lists only the verified one: %s" % manifest["platforms"])
    check(
        all(len(reason) <= 64 for reason in manifest.get("permissions", {}).values()),
        "every permission reason is at most 64 characters",
    )
    check(archive.getinfo("dqjulia/lib/libdqjulia.so").file_size > 0, "the zip carries lib/libdqjulia.so")
    check(not [n for n in archive.namelist() if "__pycache__" in n or n.endswith(".pyc")], "and no bytecode")

    # The same zip with an over-long permission reason must be refused.
    broken = os.path.join(ARGS.work, "broken.zip")
    text = archive.read(manifest_name).decode("utf-8")
    reason = manifest["permissions"]["files"]
    with zipfile.ZipFile(broken, "w") as out:
        for item in archive.infolist():
            data = archive.read(item)
            if item.filename == manifest_name:
                data = text.replace('"%s"' % reason, '"%s"' % (reason + " " + "x" * 64)).encode("utf-8")
            out.writestr(item, data)
check(validate(broken) != 0, "a manifest with a 65+ character permission reason fails the same validation")
common.finish()
