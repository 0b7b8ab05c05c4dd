#!/usr/bin/env bash
# Builds the documentation site (docs/, Sphinx with MyST-Parser) into OUT_DIR with warnings as
# errors, so a broken link, a missing anchor or a page left out of the table of contents fails it.
# The generated references (the parameter table, the command's --help, the C ABI) are made from
# the built command and the header at build time and written into OUT_DIR only.
#
#   scripts/build-docs.sh [BUILD_DIR [OUT_DIR]]   BUILD_DIR: a build tree with bin/dqjulia (build);
#                                                 OUT_DIR: where the site goes (BUILD_DIR/docs/html)
#
# Sphinx comes from scripts/tool-env.sh sphinx (made if missing). SOURCE_DATE_EPOCH, if set,
# dates the pages (scripts/release.sh sets the commit's).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out=${2:-$build/docs/html}
cli="$build/bin/dqjulia"
[ -x "$cli" ] || { echo "build-docs.sh: $cli is missing: build first (scripts/build.sh)" >&2; exit 2; }
scripts/tool-env.sh sphinx
sphinx_build=$(scripts/tool-env.sh sphinx --print)
cli=$(cd "$(dirname "$cli")" && pwd)/dqjulia
doctrees="$(dirname "$out")/.doctrees-$(basename "$out")"
# A fresh build every time (-E, its own doctrees): the references follow the command as built now.
DQJ_CLI="$cli" PYTHONDONTWRITEBYTECODE=1 "$sphinx_build" -b html -W --keep-going -E -q -d "$doctrees" docs "$out"
echo "$out"
