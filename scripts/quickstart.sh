#!/usr/bin/env bash
# The README's first command: install what is missing, build, and make the default fractal
# into out/: a picture, an OpenVDB volume, a mesh and a POV-Ray scene (a few seconds).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --build  # the tests' packages (Blender, Wine, Slurm, ...) are scripts/test.sh's
scripts/build.sh
mkdir -p out
build/bin/dqjulia render --force -o out/dqjulia.png
build/bin/dqjulia inspect > out/dqjulia-inspect.txt
build/bin/dqjulia bake --force -o out/dqjulia.vdb        # level set "surface" and fog "density", 256^3
build/bin/dqjulia mesh --force -o out/dqjulia.ply        # with normals and vertex colours
build/bin/dqjulia povray --force -o out/dqjulia.pov      # and out/dqjulia.inc beside it
echo "dqjulia: wrote out/dqjulia.png, out/dqjulia.vdb, out/dqjulia.ply, out/dqjulia.pov (and out/dqjulia-inspect.txt)"
echo "dqjulia: next: build/bin/dqjulia --help, and the add-on build/dist/dqjulia_blender.zip"
