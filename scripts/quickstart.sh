#!/usr/bin/env bash
# The README's first command: install what is missing, build, and render the default
# fractal into out/dqjulia.png.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
mkdir -p out
build/bin/dqjulia render --force -o out/dqjulia.png
build/bin/dqjulia inspect > out/dqjulia-inspect.txt
echo "dqjulia: wrote out/dqjulia.png (and out/dqjulia-inspect.txt); try: build/bin/dqjulia render --help"
