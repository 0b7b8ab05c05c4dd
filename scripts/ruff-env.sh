#!/usr/bin/env bash
# The Python linter and formatter of scripts/check-style.sh: ruff from PyPI, pinned, in a virtual
# environment cached outside the checkout in ${DQJ_RUFF_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/ruff}/<version>.
#
#   scripts/ruff-env.sh           make the venv if it is missing (about 15 MB; an existing one costs nothing)
#   scripts/ruff-env.sh --print   print its ruff (installs nothing; exit 1 if absent)
#
# As in scripts/bpy-env.sh, the venv is made in a temporary folder beside its final place and
# renamed into place only when `ruff --version` works, so a half-made one is never used.
set -euo pipefail

version=0.17.5
cache="${DQJ_RUFF_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/ruff}"
venv="$cache/$version"

if [ "${1:-}" = "--print" ]; then
  echo "$venv/bin/ruff"
  [ -x "$venv/bin/ruff" ]
  exit $?
fi
[ $# -eq 0 ] || { echo "usage: ruff-env.sh [--print]" >&2; exit 2; }

if [ -x "$venv/bin/ruff" ] && "$venv/bin/ruff" --version >/dev/null 2>&1; then
  exit 0
fi
mkdir -p "$cache"
echo "dqjulia: making the ruff $version venv in $venv" >&2
tmp="$(mktemp -d "$cache/.$version.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
python3 -m venv "$tmp/venv"
"$tmp/venv/bin/python" -m pip install --quiet --no-input --disable-pip-version-check "ruff==$version"
# bin/ruff is a native program, so the venv works under another name (only pip's #! line names
# the temporary folder: use `python -m pip`).
"$tmp/venv/bin/ruff" --version >/dev/null
rm -rf "$venv"
mv "$tmp/venv" "$venv"
