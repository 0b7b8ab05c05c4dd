#!/usr/bin/env bash
# Makes a release from this checkout's commit: dist/<version>/ with the archives, the Blender
# extension zips and their repository's index.json, the wheels and the sdist, THIRD-PARTY.json
# and SHA256SUMS (scripts/dist.py lists them).
#
#   scripts/release.sh [--no-wheels] [--no-index]
#
# - Only from a committed tree: uncommitted changes or untracked files are refused (a release is
#   its commit, which anyone can build again).
# - Builds both targets afresh in build-release/linux and build-release/windows (Release, no
#   tests; ccache makes a build of already compiled sources quick), the same way as
#   scripts/build.sh and scripts/build-windows.sh.
# - Reproducible: SOURCE_DATE_EPOCH is the commit's time; two runs from two clones give the same
#   bytes (scripts/check-reproducible.sh checks it).
# - Whole or nothing: the files are made in dist/.<version>.partial-*/ and renamed to
#   dist/<version>/ when complete; a failed run leaves no dist/<version>/ of its own, and a
#   second run replaces the first's folder whole, never mixing the two.
# - The version is VERSION's alone (scripts/set-version.sh changes it); a tag v<version> on the
#   commit is named in the log but not required.
# - --no-wheels and --no-index leave out the wheels and sdist (scripts/build-wheels.py), or the
#   extension repository's index.json (scripts/extension-repo.py, which needs the bpy venv of
#   scripts/bpy-env.sh); the folder is then dist/<version>-partial/, which cannot pass for the
#   release.
#
# Needs what scripts/install-deps.sh installs (MinGW-w64 and Wine for the Windows build, whose
# extension zip's schema is written by dqjulia.exe), and network access once for the caches
# (the third-party libraries, the bpy venv).
set -euo pipefail
cd "$(dirname "$0")/.."
dist_options=()
suffix=
for option in "$@"; do
  case "$option" in
    --no-wheels|--no-index) dist_options+=("$option"); suffix=-partial ;;
    *) echo "usage: scripts/release.sh [--no-wheels] [--no-index]" >&2; exit 2 ;;
  esac
done

if ! git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  echo "dqjulia release: $PWD is not a git checkout: a release is made from a commit" >&2
  exit 1
fi
changes=$(git status --porcelain --untracked-files=all)
if [ -n "$changes" ]; then
  echo "dqjulia release: the checkout has uncommitted changes or untracked files; a release is made" >&2
  echo "only from a commit (commit or stash them, or release from a clean clone):" >&2
  echo "$changes" | head -n 20 >&2
  exit 1
fi
version=$(cat VERSION)
commit=$(git rev-parse HEAD)
export SOURCE_DATE_EPOCH
SOURCE_DATE_EPOCH=$(git log -1 --format=%ct HEAD)
tag=$(git tag --points-at HEAD | grep -x "v$version" || true)
echo "dqjulia release: $version from $commit${tag:+ (tag $tag)}, time stamps $(date -u -d "@$SOURCE_DATE_EPOCH" +%FT%TZ)"

mkdir -p dist
exec 9>dist/.release.lock  # one release at a time in a checkout (they share build-release/)
if ! flock -n 9; then
  echo "dqjulia release: another scripts/release.sh is running in this checkout" >&2
  exit 1
fi
rm -rf build-release
echo "dqjulia release: building for Linux (build-release/linux)"
scripts/build.sh build-release/linux -DDQJ_BUILD_TESTS=OFF
echo "dqjulia release: building for Windows (build-release/windows)"
scripts/build-windows.sh build-release/windows -DDQJ_BUILD_TESTS=OFF

final="dist/$version$suffix"
partial=$(mktemp -u "dist/.$version$suffix.partial-XXXXXX")
trap 'rm -rf "$partial" "$partial.stage"' EXIT
python3 scripts/dist.py --linux-build build-release/linux --windows-build build-release/windows \
  --out "$partial" "${dist_options[@]}"
if [ -e "$final" ]; then  # the last run's folder: replaced whole
  old=$(mktemp -u "dist/.$version$suffix.old-XXXXXX")
  mv "$final" "$old"
  mv "$partial" "$final"
  rm -rf "$old"
else
  mv "$partial" "$final"
fi
echo "dqjulia release: $final"
(cd "$final" && cat SHA256SUMS)
