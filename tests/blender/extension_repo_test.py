"""scripts/extension-repo.py on its own (no Blender running; Blender's tooling from the bpy venv):

  python3 tests/blender/extension_repo_test.py --zip build/dist/dqjulia_blender.zip --work DIR

- the same zips give the same index.json bytes in two folders (one with a space in its path),
  whatever order they are given in; the index lists each zip with its platform, size and hash;
  a folder's other files are left alone;
- bad input is refused with a message naming the problem, and nothing is written: a file that
  is not a zip, a zip that is no extension, a manifest Blender's validation refuses, two zips of
  one name, two zips of one version claiming one platform.
"""

import argparse
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "extension-repo.py")
MANIFEST = "dqjulia/blender_manifest.toml"
failures = []


def check(condition, message):
    print("%s %s" % ("ok  " if condition else "FAIL", message), flush=True)
    if not condition:
        failures.append(message)


def relabelled(source, target, change):
    """A copy of the zip with its manifest's text passed through change()."""
    with zipfile.ZipFile(source) as archive, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as out:
        for item in archive.infolist():
            data = archive.read(item)
            if item.filename == MANIFEST:
                data = change(data.decode("utf-8")).encode("utf-8")
            out.writestr(item, data)
    return target


def run(*args):
    result = subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)
    return result.returncode, (result.stdout + result.stderr).strip()


def tool_venv_or_skip():
    """The bpy venv whose tooling extension-repo.py runs; missing: skipped, or failing under CI
    (tests/script_support.cmake's rule)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("extension_repo", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    series = module.TOOL_SERIES
    bpy_env = os.path.join(ROOT, "scripts", "bpy-env.sh")
    if subprocess.run([bpy_env, "--print", series], capture_output=True).returncode != 0:
        reason = "the bpy %s venv is missing: run scripts/bpy-env.sh %s" % (series, series)
        if os.environ.get("CI") == "true":
            raise SystemExit(reason + " (CI=true: every test must run)")
        print("DQJ_TEST_SKIPPED: " + reason)
        raise SystemExit(0)


def main():
    tool_venv_or_skip()
    parser = argparse.ArgumentParser()
    parser.add_argument("--zip", required=True)
    parser.add_argument("--work", required=True)
    args = parser.parse_args()
    shutil.rmtree(args.work, ignore_errors=True)
    zips = os.path.join(args.work, "zips")
    os.makedirs(zips)
    linux = os.path.join(zips, "dqjulia_blender-linux-x64.zip")
    shutil.copyfile(args.zip, linux)
    windows = relabelled(
        args.zip,
        os.path.join(zips, "dqjulia_blender-windows-x64.zip"),
        lambda text: re.sub(r"(?m)^platforms = \[[^]\n]*\]", 'platforms = ["windows-x64"]', text),
    )

    first, second = os.path.join(args.work, "one"), os.path.join(args.work, "two and three")
    os.makedirs(second)
    with open(os.path.join(second, "README.txt"), "w") as handle:
        handle.write("another file of the release")
    status, output = run(linux, windows, "--out", first)
    check(status == 0, "extension-repo.py wrote a repository: %s" % output)
    status, output = run(windows, linux, "--out", second)
    check(status == 0, "and another, the zips given the other way round")
    with open(os.path.join(first, "index.json"), "rb") as a, open(os.path.join(second, "index.json"), "rb") as b:
        check(a.read() == b.read(), "both index.json files are the same bytes")
    with open(os.path.join(first, "index.json")) as handle:
        index = json.load(handle)
    listed = {}
    for entry in index["data"]:
        path = os.path.join(first, entry["archive_url"][2:])
        with open(path, "rb") as handle:
            digest = hashlib.sha256(handle.read()).hexdigest()
        listed[os.path.basename(path)] = entry["platforms"]
        check(
            entry["archive_hash"] == "sha256:" + digest and entry["archive_size"] == os.path.getsize(path),
            "%s: its size and hash are the file's" % os.path.basename(path),
        )
    check(
        listed == {os.path.basename(linux): ["linux-x64"], os.path.basename(windows): ["windows-x64"]},
        "the index lists each zip with its platform: %s" % listed,
    )
    check(os.path.isfile(os.path.join(second, "README.txt")), "the folder's other files are left alone")

    not_zip = os.path.join(zips, "not-a-zip.zip")
    with open(not_zip, "w") as handle:
        handle.write("text")
    no_extension = os.path.join(zips, "no-extension.zip")
    with zipfile.ZipFile(no_extension, "w") as out:
        out.writestr("readme.txt", "no manifest")
    bad_manifest = relabelled(
        args.zip, os.path.join(zips, "bad-manifest.zip"), lambda text: text.replace('id = "dqjulia"', 'id = "dq julia"')
    )
    same_name = os.path.join(args.work, "elsewhere", os.path.basename(linux))
    os.makedirs(os.path.dirname(same_name))
    shutil.copyfile(linux, same_name)
    twin = os.path.join(zips, "twin.zip")
    shutil.copyfile(linux, twin)
    cases = [
        ([not_zip], "not a readable zip"),
        ([no_extension], "no blender_manifest.toml"),
        ([bad_manifest], "Blender's validation refuses"),
        ([linux, same_name], "two zips have one name"),
        ([linux, twin], "are both dqjulia"),
    ]
    for given, expected in cases:
        out = os.path.join(args.work, "refused")
        status, output = run(*given, "--out", out)
        check(
            status != 0 and expected in output and not os.path.exists(out),
            "%s: refused (%s), nothing written" % ([os.path.basename(z) for z in given], output.splitlines()[0][:110]),
        )
    if failures:
        raise SystemExit("%d check(s) failed" % len(failures))
    print("all checks passed")


main()
