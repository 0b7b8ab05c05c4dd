"""The add-on installed and updated from an extension repository, as an artist does, in a bpy wheel:

  VENV/bin/python tests/blender/repository_test.py -- --zip build/dist/dqjulia_blender.zip \\
      --windows-zip build-windows/dist/dqjulia_blender-windows-x64.zip --work DIR

1. A repository made by scripts/extension-repo.py (Blender's own server-generate) from the
   build's Linux zip and a Windows zip (the Windows build's; without one, a copy of the Linux
   zip whose manifest says windows-x64), in a folder whose name has a space, is added under
   Preferences > Get Extensions > Repositories as a remote repository with its file:// URL
   (preferences.extension_repo_add), synced, and dqjulia is installed from it and enabled
   (extensions.package_install): the Linux zip, not the Windows one.
2. The artist sets a preference (the cache folder), saves a .blend, bakes a volume and a mesh.
3. The host publishes a higher version (a copy of both zips with the manifest's version raised,
   the index made again) in the same folder: after a sync Blender counts one update (what its
   status bar shows), extensions.package_upgrade_all installs it, and the new version runs with
   the preference kept, the open .blend's objects, settings and bakes (files unchanged) intact,
   and bakes again; the .blend reopens with its bakes.
4. The same folder served over HTTP (Python's http.server on 127.0.0.1, as the README's way to
   try hosting it) syncs as a repository whose URL names its index.json, and lists the version.
5. An extension for another platform is refused with Blender's own message: the Windows zip
   installed from disk, and a repository holding only it.
"""

import hashlib
import importlib
import os
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402
from common import check, report  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MANIFEST = "dqjulia/blender_manifest.toml"
WINDOWS = "windows-x64"
LINUX = "linux-x64"


def extra_arguments(parser):
    parser.add_argument("--windows-zip", default="", help="the Windows build's extension zip, if built")


ARGS = common.arguments(extra_arguments)
PREFS = bpy.context.preferences


# -------------------------------------------------------------------------------------------
# Zips and repositories


def manifest_of(path):
    with zipfile.ZipFile(path) as archive:
        return tomllib.loads(archive.read(MANIFEST).decode("utf-8"))


def copy_with_manifest(source, target, version=None, platform=None):
    """A copy of the extension zip with its manifest's version and/or platforms changed; every
    other member byte for byte as it was."""
    with zipfile.ZipFile(source) as archive, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as out:
        for item in archive.infolist():
            data = archive.read(item)
            if item.filename == MANIFEST:
                text = data.decode("utf-8")
                if version:
                    text = re.sub(r'(?m)^version = "[^"]*"', 'version = "%s"' % version, text)
                if platform:
                    text = re.sub(r"(?m)^platforms = \[[^]\n]*\]", 'platforms = ["%s"]' % platform, text)
                data = text.encode("utf-8")
            out.writestr(item, data)
    return target


def release_zips(folder, version=None):
    """The Linux and Windows zips, named as a release names them, in `folder`."""
    os.makedirs(folder, exist_ok=True)
    number = version or manifest_of(ARGS.zip)["version"]
    linux = os.path.join(folder, "dqjulia_blender-%s-%s.zip" % (number, LINUX))
    windows = os.path.join(folder, "dqjulia_blender-%s-%s.zip" % (number, WINDOWS))
    copy_with_manifest(ARGS.zip, linux, version=version)
    if ARGS.windows_zip and os.path.isfile(ARGS.windows_zip):
        copy_with_manifest(ARGS.windows_zip, windows, version=version)
    else:
        copy_with_manifest(ARGS.zip, windows, version=version, platform=WINDOWS)
    return [linux, windows]


def make_repository(zips, folder):
    """scripts/extension-repo.py ZIP... --out folder (Blender's server-generate)."""
    result = subprocess.run(
        [sys.executable, os.path.join(ROOT, "scripts", "extension-repo.py"), *zips, "--out", folder],
        capture_output=True,
        text=True,
    )
    check(result.returncode == 0, "extension-repo.py made %s: %s" % (folder, (result.stdout + result.stderr).strip()))


def file_url(folder):
    import pathlib

    return pathlib.Path(folder).as_uri()


def raised(version):
    major, minor, patch = (int(x) for x in version.split("."))
    return "%d.%d.%d" % (major, minor, patch + 1)


def digest(path):
    with open(path, "rb") as handle:
        return hashlib.sha256(handle.read()).hexdigest()


# -------------------------------------------------------------------------------------------
# Blender's extension machinery (the core add-on bl_pkg), as the preferences' buttons drive it


def run(operator, **properties):
    """Runs an extensions operator; returns (result, its messages: [(kind, text), ...]). What the
    preferences show in their status area bl_pkg prints in background mode ("ERROR text"), and
    reports only that the operator finished: its messages are read from what it prints."""
    import contextlib
    import io

    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        result, error = common.call(operator, **properties)
    sys.stdout.write(printed.getvalue())
    messages = [tuple(line.split(" ", 1)) for line in printed.getvalue().splitlines() if " " in line]
    if error:
        messages.append(("ERROR", error))
    return result, messages


def errors_in(messages):
    return [text for kind, text in messages if kind in {"ERROR", "FATAL_ERROR"}]


def add_repository(name, folder):
    """Get Extensions > Repositories > + > Add Remote Repository, with the folder's file:// URL."""
    url = file_url(folder)
    result = bpy.ops.preferences.extension_repo_add(name=name, remote_url=url, type="REMOTE")
    repos = PREFS.extensions.repos
    index = next((i for i, repo in enumerate(repos) if repo.remote_url == url), None)
    check(result == {"FINISHED"} and index is not None, "repository %r added: %s" % (name, url))
    return index


def sync(index):
    # The operators take the repository's folder: their repo_index counts the enabled
    # repositories only (the official one is off here).
    repo = PREFS.extensions.repos[index]
    result, messages = run(bpy.ops.extensions.repo_sync, repo_directory=repo.directory)
    errors = errors_in(messages)
    check(result == {"FINISHED"} and not errors, "synced %r%s" % (repo.name, ": %s" % errors if errors else ""))


def updates(index):
    """How many installed extensions of the repository have a newer version: the count
    Blender's status bar and the Get Extensions tab offer as updates."""
    import bl_pkg

    directory = PREFS.extensions.repos[index].directory
    return bl_pkg.repo_stats_calc_outdated_for_repo_directory(bl_pkg.repo_cache_store_ensure(), directory)


def installed_version(module):
    import addon_utils

    return addon_utils.module_bl_info(importlib.import_module(module))["version"]


# -------------------------------------------------------------------------------------------
# The scene


def baked(obj, kind):
    return next((child for child in obj.children if child.get("dqjulia_bake") == kind), None)


def bake_scene(blend):
    """A saved .blend with a DQ Julia object (one setting changed) baked as a volume and a mesh."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    os.makedirs(os.path.dirname(blend), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    check(bpy.ops.object.dqjulia_add() == {"FINISHED"}, "Add DQ Julia")
    obj = bpy.context.view_layer.objects.active
    obj.dqjulia.iterations = 11
    obj.dqjulia.bake_resolution = 48
    obj.select_set(True)
    for operator in (bpy.ops.dqjulia.bake_volume, bpy.ops.dqjulia.bake_mesh):
        result, error = common.call(operator, synchronous=True)
        check(result == {"FINISHED"}, "%s%s" % (operator.idname_py(), ": " + error if error else ""))
    bpy.ops.wm.save_mainfile()
    return obj


def scene_state(obj):
    """What must survive an update: the object's settings, its bakes and their files."""
    volume, mesh = baked(obj, "volume"), baked(obj, "mesh")
    path = bpy.path.abspath(volume.data.filepath) if volume else ""
    if volume:
        volume.data.grids.load()
    return {
        "iterations": obj.dqjulia.iterations,
        "volume file": path,
        "volume bytes": digest(path) if os.path.isfile(path) else None,
        "grids": sorted(grid.name for grid in volume.data.grids) if volume else [],
        "mesh vertices": len(mesh.data.vertices) if mesh else 0,
        "mesh faces": len(mesh.data.polygons) if mesh else 0,
    }


# -------------------------------------------------------------------------------------------
# The steps


def step_install(index):
    repo = PREFS.extensions.repos[index]
    result, messages = run(
        bpy.ops.extensions.package_install,
        repo_directory=repo.directory,
        pkg_id="dqjulia",
        enable_on_install=True,
    )
    module = "bl_ext.%s.dqjulia" % repo.module
    check(
        result == {"FINISHED"} and module in PREFS.addons and not errors_in(messages),
        "installed and enabled %s %s" % (module, errors_in(messages)),
    )
    folder = os.path.join(repo.directory, "dqjulia")
    check(
        os.path.isfile(os.path.join(folder, "lib", "libdqjulia.so"))
        and not os.path.exists(os.path.join(folder, "lib", "dqjulia.dll"))
        and manifest_of_folder(folder)["platforms"] == [LINUX],
        "Blender chose the %s zip" % LINUX,
    )
    native = importlib.import_module(module + ".native")
    check(native.load_error() is None, "its library loads: %s" % native.load_error())
    return module


def manifest_of_folder(folder):
    with open(os.path.join(folder, "blender_manifest.toml"), "rb") as handle:
        return tomllib.load(handle)


def step_update(index, module, version, obj, site, new_zips):
    cache = PREFS.addons[module].preferences.cache_dir
    name = obj.name
    before = scene_state(obj)
    check(before["volume file"].startswith(cache) and before["volume bytes"], "the bake is in the chosen cache")
    check(updates(index) == 0, "nothing to update while the repository has %s" % version)

    new_version = manifest_of(new_zips[0])["version"]
    shutil.rmtree(site)
    make_repository(new_zips, site)  # the host replaces the folder's contents
    sync(index)
    check(updates(index) == 1, "after a sync Blender offers 1 update (%d)" % updates(index))
    result, messages = run(bpy.ops.extensions.package_upgrade_all)
    check(result == {"FINISHED"} and not errors_in(messages), "Install Available Updates %s" % errors_in(messages))
    expected = tuple(int(x) for x in new_version.split("."))
    check(installed_version(module) == expected, "dqjulia %s runs (%s)" % (new_version, installed_version(module)))
    check(updates(index) == 0, "and no update is offered any more")
    check(module in PREFS.addons, "the add-on is still enabled")
    check(PREFS.addons[module].preferences.cache_dir == cache, "the preference (cache folder) is kept")
    obj = bpy.data.objects[name]
    after = scene_state(obj)
    check(after == before, "the open .blend's settings and bakes are intact: %s" % after)
    check(bpy.ops.dqjulia.bake_volume(synchronous=True) == {"FINISHED"}, "the new version bakes the object again")
    bpy.ops.wm.save_mainfile()
    blend = bpy.data.filepath
    bpy.ops.wm.open_mainfile(filepath=blend)
    reopened = scene_state(bpy.data.objects[name])
    check(
        reopened["grids"] == before["grids"] and os.path.isfile(reopened["volume file"]),
        "the .blend reopens with its bakes: %s" % reopened["grids"],
    )


def step_http(site, version):
    """The repository folder served by a web server (on this machine's loopback only)."""
    import functools
    import http.server
    import json
    import threading

    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=site)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        url = "http://127.0.0.1:%d/index.json" % server.server_address[1]
        result = bpy.ops.preferences.extension_repo_add(name="web", remote_url=url, type="REMOTE")
        index = next(i for i, repo in enumerate(PREFS.extensions.repos) if repo.remote_url == url)
        check(result == {"FINISHED"}, "repository added: %s" % url)
        sync(index)
        with open(os.path.join(PREFS.extensions.repos[index].directory, ".blender_ext", "index.json")) as handle:
            listed = {(entry["id"], entry["version"]) for entry in json.load(handle)["data"]}
        check(listed == {("dqjulia", version)}, "over HTTP it lists dqjulia %s: %s" % (version, sorted(listed)))
        PREFS.extensions.repos.remove(PREFS.extensions.repos[index])
    finally:
        server.shutdown()
        server.server_close()


def step_wrong_platform(windows_zip):
    user_default = next(repo for repo in PREFS.extensions.repos if repo.module == "user_default").directory
    os.makedirs(user_default, exist_ok=True)
    _result, messages = run(
        bpy.ops.extensions.package_install_files, filepath=windows_zip, repo="user_default", enable_on_install=True
    )
    refusal = "This platform (%s) isn't one of (%s)" % (LINUX, WINDOWS)
    check(
        any(refusal in text for text in errors_in(messages)),
        "Install from Disk of the Windows zip is refused: %s" % errors_in(messages),
    )
    check(not os.path.exists(os.path.join(user_default, "dqjulia")), "and installs nothing")

    folder = os.path.join(ARGS.work, "windows only")
    make_repository([windows_zip], folder)
    index = add_repository("Windows only", folder)
    sync(index)
    _result, messages = run(
        bpy.ops.extensions.package_install,
        repo_directory=PREFS.extensions.repos[index].directory,
        pkg_id="dqjulia",
        enable_on_install=True,
    )
    check(
        any('"dqjulia", found but not compatible with this system' in text for text in errors_in(messages)),
        "a repository holding only the Windows zip: install refused: %s" % errors_in(messages),
    )
    repo = PREFS.extensions.repos[index]
    check(not os.path.exists(os.path.join(repo.directory, "dqjulia")), "and nothing installed")


def main():
    import addon_utils

    report("Blender %s: dqjulia from an extension repository" % bpy.app.version_string)
    if "repo_sync" not in dir(bpy.ops.extensions):
        addon_utils.enable("bl_pkg", default_set=True)
    # Installing from a repository needs online access, even from a file:// URL (Blender says
    # so in the Get Extensions tab); the official repository stays off: no network in a test.
    PREFS.system.use_online_access = True
    for repo in PREFS.extensions.repos:
        if repo.use_remote_url and not repo.remote_url.startswith("file:"):
            repo.enabled = False

    version = manifest_of(ARGS.zip)["version"]
    zips = release_zips(os.path.join(ARGS.work, "release %s" % version))
    site = os.path.join(ARGS.work, "studio share", "dqjulia")
    make_repository(zips, site)
    index = add_repository("dqjulia", site)
    sync(index)
    module = step_install(index)
    PREFS.addons[module].preferences.cache_dir = os.path.join(ARGS.work, "my cache")  # the artist's choice
    obj = bake_scene(os.path.join(ARGS.work, "project", "scene.blend"))
    new_zips = release_zips(os.path.join(ARGS.work, "release next"), raised(version))
    step_update(index, module, version, obj, site, new_zips)
    step_http(site, manifest_of(new_zips[0])["version"])
    step_wrong_platform(zips[1])
    common.finish()


main()
