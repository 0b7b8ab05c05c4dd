#!/usr/bin/env bash
# One Python virtual environment per Blender version the add-on is tested in, each with the
# official `bpy` wheel from PyPI (Blender as a Python module), cached outside the
# checkout in ${DQJ_BPY_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/bpy}/<exact version>.
#
#   scripts/bpy-env.sh                   make the venvs that are missing (all versions)
#   scripts/bpy-env.sh 4.5               only that series (or an exact version: 4.5.15)
#   scripts/bpy-env.sh --print 4.5       print that venv's python (installs nothing; exit 1 if absent)
#   scripts/bpy-env.sh --list            print the exact versions, one a line
#
# A venv is built in a temporary folder beside its final place and renamed into place only when
# `import bpy` works, so a half-made one is never used; an existing one costs nothing. Its
# requirements (the wheel and numpy, pinned) are kept in it: when they change, it is remade.
# The wheels need CPython 3.11 (DQJ_BPY_PYTHON, default python3). Each is 200-320 MB; the
# wheels' own dependencies (numpy, requests, zstandard, cython: declared by every bpy wheel)
# come with them from PyPI; the add-on and its tests need none of them (tests/blender).
set -euo pipefail

# The newest release of each series that PyPI has (the LTS series 4.2 and 4.5, and 5.0).
versions=(4.2.23 4.5.15 5.0.1)
cache="${DQJ_BPY_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/bpy}"
python="${DQJ_BPY_PYTHON:-python3}"

exact() {  # a series (4.5) or an exact version (4.5.15) -> the pinned exact version
  local v
  for v in "${versions[@]}"; do
    if [ "$v" = "$1" ] || [ "${v%.*}" = "$1" ]; then
      echo "$v"
      return 0
    fi
  done
  echo "bpy-env.sh: no pinned bpy version for '$1' (known: ${versions[*]})" >&2
  return 1
}

requirements() {  # what a venv holds, one a line; kept in the venv as $stamp
  # numpy: the wheels 4.5 and 5.0 require >=1.26,<2 (and get 1.26.4); 4.2.23 names numpy
  # unpinned, which would bring numpy 2 beside a Blender built against 1.26: 1.26.4 for all.
  printf 'bpy==%s\nnumpy==1.26.4\n' "$1"
}
stamp=dqjulia-requirements.txt

ready() {  # the venv exists, complete, with these requirements
  [ -x "$1/bin/python" ] && [ "$(cat "$1/$stamp" 2>/dev/null)" = "$(requirements "$2")" ]
}

if [ "${1:-}" = "--list" ]; then
  printf '%s\n' "${versions[@]}"
  exit 0
fi
if [ "${1:-}" = "--print" ]; then
  [ $# -eq 2 ] || { echo "usage: bpy-env.sh --print VERSION" >&2; exit 2; }
  v="$(exact "$2")"
  echo "$cache/$v/bin/python"
  ready "$cache/$v" "$v"
  exit $?
fi

wanted=()
if [ $# -eq 0 ]; then
  wanted=("${versions[@]}")
else
  for a in "$@"; do wanted+=("$(exact "$a")"); done
fi

checked=""
for v in "${wanted[@]}"; do
  final="$cache/$v"
  if ready "$final" "$v"; then
    continue
  fi
  if [ -z "$checked" ]; then
    "$python" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' || {
      echo "bpy-env.sh: the bpy wheels need CPython 3.11; $python is $("$python" --version 2>&1)" \
           "(set DQJ_BPY_PYTHON)" >&2
      exit 1
    }
    mkdir -p "$cache"
    checked=yes
  fi
  echo "bpy-env.sh: making the venv for bpy==$v in $final" >&2
  tmp="$(mktemp -d "$cache/.$v.XXXXXX")"
  # bin/python and `python -m pip` do not depend on the venv's folder name, so it is built at a
  # temporary name and moved (only the console scripts' #! lines, bin/pip for one, name the
  # temporary folder: use `python -m pip`).
  trap 'rm -rf "$tmp"' EXIT
  "$python" -m venv "$tmp/venv"
  requirements "$v" > "$tmp/requirements.txt"
  "$tmp/venv/bin/python" -m pip install --quiet --no-input -r "$tmp/requirements.txt"
  "$tmp/venv/bin/python" -c 'import bpy, sys; print("bpy", bpy.app.version_string, file=sys.stderr)'
  cp "$tmp/requirements.txt" "$tmp/venv/$stamp"
  if ! ready "$final" "$v"; then  # (another run may have finished it meanwhile)
    rm -rf "$final"
    mv "$tmp/venv" "$final"
  fi
  rm -rf "$tmp"
  trap - EXIT
done
