#!/usr/bin/env bash
# Checks that a release is reproducible: clones this checkout's commit twice, into two folders of
# different paths, runs scripts/release.sh in each, and compares the two dist/<version>/ folders
# byte for byte (their SHA256SUMS, then scripts/dist-diff.py: where they differ, down to the
# entries of the archives, and whether any file names either clone's path).
#
#   scripts/check-reproducible.sh [--ccache] [--no-wheels] [--no-index] [--keep-dist DIR]
#
# The second clone is built without ccache (CCACHE_DISABLE=1), so the check also shows that a
# build from the compiler alone gives the bytes of one from the cache (about 20 minutes more on
# 2 cores); --ccache lets it use the cache too (quick). --no-wheels and --no-index are passed to
# scripts/release.sh. --keep-dist DIR keeps the first release's dist/<version>/ in DIR (made; it
# must not exist) when the check passes, to inspect or publish it. Prints both SHA256SUMS; the clones are removed when the check passes and
# kept (their folder printed) when it fails. Uncommitted changes are not part of the check.
set -euo pipefail
cd "$(dirname "$0")/.."
use_ccache=0 keep_dist=""
options=()
while [ $# -gt 0 ]; do
  case "$1" in
    --ccache) use_ccache=1 ;;
    --no-wheels|--no-index) options+=("$1") ;;
    --keep-dist)
      keep_dist=${2:?--keep-dist needs a folder}
      [ ! -e "$keep_dist" ] || { echo "dqjulia reproducible: $keep_dist exists already" >&2; exit 2; }
      shift ;;
    *) echo "usage: scripts/check-reproducible.sh [--ccache] [--no-wheels] [--no-index] [--keep-dist DIR]" >&2; exit 2 ;;
  esac
  shift
done
commit=$(git rev-parse HEAD)
if [ -n "$(git status --porcelain --untracked-files=all)" ]; then
  echo "dqjulia reproducible: note: uncommitted changes are not checked, only the commit $commit" >&2
fi
work=$(mktemp -d "${TMPDIR:-/tmp}/dqjulia-reproducible-XXXXXX")
first=$work/first
second=$work/another/path/for/the/second-clone
start=$(date +%s)

release() {  # release CLONE LOG [ENVIRONMENT...]
  local clone=$1 log=$2
  shift 2
  git clone --quiet --no-hardlinks "$PWD" "$clone"
  git -C "$clone" checkout --quiet --detach "$commit"
  echo "dqjulia reproducible: releasing $commit in $clone ($*)"
  if ! (cd "$clone" && env "$@" scripts/release.sh "${options[@]}") >"$log" 2>&1; then
    tail -n 40 "$log" >&2
    echo "dqjulia reproducible: the release failed in $clone (log: $log; kept: $work)" >&2
    exit 1
  fi
}
release "$first" "$work/first.log" DQJ_REPRODUCIBLE_RUN=1
if [ "$use_ccache" = 1 ]; then
  release "$second" "$work/second.log" DQJ_REPRODUCIBLE_RUN=2
else
  release "$second" "$work/second.log" CCACHE_DISABLE=1
fi

dist_a=$(find "$first/dist" -mindepth 1 -maxdepth 1 -type d -not -name '.*')
dist_b=$(find "$second/dist" -mindepth 1 -maxdepth 1 -type d -not -name '.*')
echo "== $dist_a/SHA256SUMS"
cat "$dist_a/SHA256SUMS"
echo "== $dist_b/SHA256SUMS"
cat "$dist_b/SHA256SUMS"
if cmp -s "$dist_a/SHA256SUMS" "$dist_b/SHA256SUMS" \
   && python3 scripts/dist-diff.py "$dist_a" "$dist_b" --forbid "$first" --forbid "$second" >/dev/null; then
  echo "dqjulia reproducible: the same bytes, no clone's path in them ($(($(date +%s) - start)) s)"
  if [ -n "$keep_dist" ]; then
    mkdir -p "$(dirname "$keep_dist")"
    mv "$dist_a" "$keep_dist"
    echo "dqjulia reproducible: the first release kept in $keep_dist"
  fi
  rm -rf "$work"
  exit 0
fi
python3 scripts/dist-diff.py "$dist_a" "$dist_b" --forbid "$first" --forbid "$second" || true
echo "dqjulia reproducible: the two releases differ (kept: $work)" >&2
exit 1
