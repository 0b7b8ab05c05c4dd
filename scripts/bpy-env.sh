#!/usr/bin/env bash
# One Python virtual environment per Blender version the add-on is tested in, each with the
# official `bpy` wheel from PyPI (Blender as a Python module), cached outside the
# checkout in ${DQJ_BPY_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/bpy}/<exact version>.
#
#   scripts/bpy-env.sh                   make the venvs that are missing (all versions)
#   scripts/bpy-env.sh 5.2               only that series (or an exact version: 5.2.4)
#   scripts/bpy-env.sh --print 5.2       print that venv's python (installs nothing; exit 1 if absent)
#   scripts/bpy-env.sh --list            print the exact versions, one a line
#
# A venv is built in a temporary folder beside its final place and renamed into place only when
# `import bpy` works, so a half-made one is never used; an existing one costs nothing. Its
# requirements (the wheel and numpy, pinned) and the CPython it was made with are kept in it:
# when they change, it is remade. Each wheel is 250-400 MB; the wheels' own dependencies
# (numpy, requests, zstandard, cython, and cattrs from 5.1) come with them from PyPI.
#
# Each series needs one CPython (the wheels are built for exactly one):
#   4.2, 4.5   CPython 3.11: $DQJ_BPY_PYTHON, else python3 (Debian 12's is 3.11)
#   5.1 and on CPython 3.13: $DQJ_BPY_PYTHON313, else pyenv's newest 3.13, else python3.13 on
#              PATH, else python3 if it is 3.13 (Debian 13's), else (as root, where
#              scripts/debian-root.sh exists) the python3 of a Debian 13 root made by
#              scripts/debian-root.sh trixie, run on this machine with that root's own loader
#              and libraries (no chroot: a launcher in $cache/cpython-3.13-trixie/bin), so a
#              Debian 12 without pyenv runs the 5.x wheels too
set -euo pipefail

# The newest release of each series that PyPI has: the floor the manifest admits (4.2, whose LTS
# support ended in July 2026), the LTS series 4.5 and 5.2, and the newest release, 5.3. 5.0 and
# 5.1 were ordinary releases, each replaced by the next after four months (docs/blender.md, "Supported
# Blender versions").
versions=(4.2.23 4.5.15 5.2.4 5.3.0)
cache="${DQJ_BPY_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/bpy}"
here="$(cd "$(dirname "$0")" && pwd)"
trixie="$cache/cpython-3.13-trixie"  # the launcher of a Debian 13 root's CPython (trixie_cpython)

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

cpython_of() {  # the CPython series a bpy version's wheel is built for
  case "$1" in
    4.*) echo 3.11 ;;
    *) echo 3.13 ;;
  esac
}

requirements() {  # what a venv holds, one a line; kept in the venv as $stamp
  # numpy: the wheels 4.5 require >=1.26,<2 (and get 1.26.4); 4.2.23 names numpy unpinned, which
  # would bring numpy 2 beside a Blender built against 1.26: 1.26.4 for both. 5.1+ require
  # >=2.2,<3.
  case "$1" in
    4.*) printf 'bpy==%s\nnumpy==1.26.4\n' "$1" ;;
    *) printf 'bpy==%s\nnumpy==2.5.5\n' "$1" ;;
  esac
}
stamp=dqjulia-requirements.txt

ready() {  # the venv exists, complete, with these requirements
  [ -x "$1/bin/python" ] && [ "$(cat "$1/$stamp" 2>/dev/null)" = "$(requirements "$2")" ]
}

is_cpython() {  # is_cpython PROGRAM 3.13: the program runs and is that CPython
  [ -n "$1" ] && "$1" -c "import sys; sys.exit(sys.version_info[:2] != tuple(map(int, '$2'.split('.'))))" \
    >/dev/null 2>&1
}

trixie_cpython() {  # a launcher of a Debian 13 root's CPython 3.13, made if missing; prints its path
  local root launcher folder="$trixie"
  [ "$(id -u)" -eq 0 ] && [ -x "$here/debian-root.sh" ] || return 1
  echo "bpy-env.sh: no CPython 3.13 here: taking a Debian 13 root's (scripts/debian-root.sh trixie)" >&2
  root="$("$here/debian-root.sh" trixie --with python3 python3-venv)" || return 1
  [ -x "$root/usr/bin/python3.13" ] || return 1
  # The root's python3.13 needs its own glibc: run it through the root's dynamic loader with the
  # root's libraries. --argv0 keeps the name it was started by, so a venv's bin/python (a link to
  # the launcher) finds its pyvenv.cfg and sys.executable starts the venv again; lib/ beside bin/
  # is the root's, where Python finds its standard library.
  mkdir -p "$folder/bin"
  ln -sfn "$root/usr/lib" "$folder/lib"
  launcher="$folder/bin/python3.13"
  cat > "$launcher.tmp" <<LAUNCHER
#!/bin/sh
# CPython 3.13 of the Debian 13 root $root (scripts/bpy-env.sh)
exec "$root/usr/lib/x86_64-linux-gnu/ld-linux-x86-64.so.2" --library-path "$root/usr/lib/x86_64-linux-gnu" \\
  --argv0 "\$0" "$root/usr/bin/python3.13" "\$@"
LAUNCHER
  chmod 755 "$launcher.tmp"
  mv "$launcher.tmp" "$launcher"
  is_cpython "$launcher" 3.13 && echo "$launcher"
}

find_cpython() {  # find_cpython 3.11|3.13 -> a program of that CPython, or an explanation on stderr
  local wanted="$1" candidate root newest
  local -a candidates=()
  if [ "$wanted" = 3.11 ]; then
    candidates+=("${DQJ_BPY_PYTHON:-python3}")
  else
    if [ -n "${DQJ_BPY_PYTHON313:-}" ]; then
      candidates+=("$DQJ_BPY_PYTHON313")
    fi
    if command -v pyenv >/dev/null 2>&1; then
      root="$(pyenv root)"
      newest="$(pyenv versions --bare 2>/dev/null | grep -E '^3\.13\.[0-9]+$' | sort -V | tail -n 1 || true)"
      if [ -n "$newest" ]; then
        candidates+=("$root/versions/$newest/bin/python3.13")
      fi
    fi
    candidates+=("$(command -v python3.13 || true)" python3)
  fi
  for candidate in "${candidates[@]}"; do
    if is_cpython "$candidate" "$wanted"; then
      command -v "$candidate"
      return 0
    fi
  done
  if [ "$wanted" = 3.13 ] && trixie_cpython; then
    return 0
  fi
  if [ "$wanted" = 3.11 ]; then
    echo "bpy-env.sh: the bpy wheels 4.x need CPython 3.11; ${DQJ_BPY_PYTHON:-python3} is" \
         "$("${DQJ_BPY_PYTHON:-python3}" --version 2>&1) (set DQJ_BPY_PYTHON to a CPython 3.11)" >&2
  else
    echo "bpy-env.sh: the bpy wheels 5.1 and later need CPython 3.13, and none was found" \
         "(tried ${DQJ_BPY_PYTHON313:+DQJ_BPY_PYTHON313=$DQJ_BPY_PYTHON313, }pyenv, python3.13, python3," \
         "and a Debian 13 root's, which needs root and scripts/debian-root.sh):" \
         "set DQJ_BPY_PYTHON313 to a CPython 3.13" >&2
  fi
  return 1
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

for v in "${wanted[@]}"; do
  final="$cache/$v"
  if ready "$final" "$v"; then
    continue
  fi
  python="$(find_cpython "$(cpython_of "$v")")"
  pip_wheel=""
  if [ "$python" = "$trixie/bin/python3.13" ]; then
    # Its ensurepip would install this machine's pip wheel (Debian's, for its own Python): the root's.
    pip_wheel="$(ls "$(readlink -f "$trixie/lib/..")"/share/python-wheels/pip-*.whl | head -n 1)"
  fi
  mkdir -p "$cache"
  echo "bpy-env.sh: making the venv for bpy==$v ($("$python" --version 2>&1), $python) in $final" >&2
  tmp="$(mktemp -d "$cache/.$v.XXXXXX")"
  # bin/python and `python -m pip` do not depend on the venv's folder name, so it is built at a
  # temporary name and moved (only the console scripts' #! lines, bin/pip for one, name the
  # temporary folder: use `python -m pip`).
  trap 'rm -rf "$tmp"' EXIT
  if [ -n "$pip_wheel" ]; then  # the Debian 13 root's CPython: pip from the root's wheel
    "$python" -m venv --without-pip "$tmp/venv"
    "$tmp/venv/bin/python" "$pip_wheel/pip" install --quiet --no-index "$pip_wheel"
  else
    "$python" -m venv "$tmp/venv"
  fi
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
