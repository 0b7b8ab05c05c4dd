#!/usr/bin/env bash
# A pinned command-line tool from PyPI in a virtual environment cached outside the checkout, in
# ${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/<tool>/<version> (or $DQJ_RUFF_CACHE, $DQJ_OPENJD_CACHE, ...):
#   ruff        the Python linter and formatter of scripts/check-style.sh (about 15 MB)
#   mypy        the type checker of scripts/check-style.sh (mypy.ini; about 90 MB): 1.20, the last
#               that checks code for Python 3.9, which the Python package and native.py support
#   openjd      Open Job Description's reference runner for tests/farm (openjd-cli, about 20 MB)
#   auditwheel  PyPA's checker of a Linux wheel's platform tag, for tests/python (about 10 MB)
#   twine       PyPA's uploader, whose `twine check` tests/python runs on the wheels and the sdist (about 15 MB)
#   sphinx      the documentation site's builder (docs/, tests/docs, scripts/release.sh): Sphinx with
#               MyST-Parser for the Markdown pages and the Furo theme, pinned together (about 60 MB);
#               its program is sphinx-build
#   meshcheck   the independent readers of the mesh tests (tests/core/mesh_files_test.py): trimesh
#               (watertight and edge-manifold checks of every mesh format) with lxml and networkx for
#               its 3MF loader, and lib3mf, the 3MF consortium's library, through its Python binding
#               (about 120 MB); its program is python
#
#   scripts/tool-env.sh TOOL           make the venv if it is missing (an existing one costs nothing)
#   scripts/tool-env.sh TOOL --print   print the tool's program (installs nothing; exit 1 if absent)
#
# As in scripts/bpy-env.sh, the venv is made in a temporary folder beside its final place and
# renamed into place once pip has finished, so a half-made one is never used; one whose
# `TOOL --version` fails is made again.
set -euo pipefail

usage() { echo "usage: tool-env.sh ruff|mypy|openjd|auditwheel|twine|sphinx|meshcheck [--print]" >&2; exit 2; }
[ $# -ge 1 ] || usage
tool="$1"
shift
case "$tool" in
  ruff) version=0.17.5 package="ruff==$version" cache="${DQJ_RUFF_CACHE:-}" ;;
  mypy) version=1.20.2 package="mypy==$version" cache="${DQJ_MYPY_CACHE:-}" ;;
  openjd) version=0.8.0 package="openjd-cli==$version" cache="${DQJ_OPENJD_CACHE:-}" ;;
  auditwheel) version=6.8.2 package="auditwheel==$version" cache="${DQJ_AUDITWHEEL_CACHE:-}" ;;
  twine) version=6.2.0 package="twine==$version" cache="${DQJ_TWINE_CACHE:-}" ;;
  # One venv of three pinned packages: the folder's name carries every pin.
  sphinx) version=9.0.4-myst5.0.0-furo2025.12.19 program_name=sphinx-build
          package="sphinx==9.0.4 myst-parser==5.0.0 furo==2025.12.19" cache="${DQJ_SPHINX_CACHE:-}" ;;
  meshcheck) version=trimesh5.2.0-lib3mf2.5.0 program_name=python
             package="trimesh==5.2.0 numpy==2.4.6 lxml==6.1.3 networkx==3.6.1 lib3mf==2.5.0"
             cache="${DQJ_MESHCHECK_CACHE:-}" ;;
  *) usage ;;
esac
cache="${cache:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/$tool}"
venv="$cache/$version"
program="$venv/bin/${program_name:-$tool}"

if [ "${1:-}" = "--print" ]; then
  echo "$program"
  [ -x "$program" ]
  exit $?
fi
[ $# -eq 0 ] || usage

if [ -x "$program" ] && "$program" --version >/dev/null 2>&1; then
  exit 0
fi
mkdir -p "$cache"
echo "dqjulia: making the $package venv in $venv" >&2
tmp="$(mktemp -d "$cache/.$version.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
python3 -m venv "$tmp/venv"
# `python -m pip`: pip's own #! line would name the temporary folder after the move.
# shellcheck disable=SC2086  # $package: one or more requirements
"$tmp/venv/bin/python" -m pip install --quiet --no-input --disable-pip-version-check $package
rm -rf "$venv"
mv "$tmp/venv" "$venv"
# A Python entry point's #! line names the venv's python: after the move, point it there (ruff's
# program is native and has none).
if [ "$(head -c 2 "$program")" = "#!" ]; then
  sed -i "1s|^#!.*|#!$venv/bin/python|" "$program"
fi
"$program" --version >/dev/null
