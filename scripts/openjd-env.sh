#!/usr/bin/env bash
# Open Job Description's reference runner for tests/farm: openjd-cli from PyPI, pinned, in a
# virtual environment cached outside the checkout in
# ${DQJ_OPENJD_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/openjd}/<version> (as scripts/ruff-env.sh does for ruff).
#
#   scripts/openjd-env.sh           make the venv if it is missing (about 20 MB; an existing one costs nothing)
#   scripts/openjd-env.sh --print   print its openjd (installs nothing; exit 1 if absent)
#
# The venv is made in a temporary folder beside its final place and renamed into place only when
# `openjd --version` works, so a half-made one is never used.
set -euo pipefail

version=0.8.0
cache="${DQJ_OPENJD_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/openjd}"
venv="$cache/$version"

if [ "${1:-}" = "--print" ]; then
  echo "$venv/bin/openjd"
  [ -x "$venv/bin/openjd" ]
  exit $?
fi
[ $# -eq 0 ] || { echo "usage: openjd-env.sh [--print]" >&2; exit 2; }

if [ -x "$venv/bin/openjd" ] && "$venv/bin/openjd" --version >/dev/null 2>&1; then
  exit 0
fi
mkdir -p "$cache"
echo "dqjulia: making the openjd-cli $version venv in $venv" >&2
tmp="$(mktemp -d "$cache/.$version.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
python3 -m venv "$tmp/venv"
"$tmp/venv/bin/python" -m pip install --quiet --no-input --disable-pip-version-check "openjd-cli==$version"
rm -rf "$venv"
mv "$tmp/venv" "$venv"
# openjd is a Python entry point whose #! line names the venv's python: after the move, point it there.
sed -i "1s|^#!.*|#!$venv/bin/python|" "$venv/bin/openjd"
"$venv/bin/openjd" --version >/dev/null
