#!/usr/bin/env bash
# Installs the Debian packages dqjulia needs to build and test, if any are missing.
# Usage: scripts/install-deps.sh [MORE PACKAGES...]   (as root, or with sudo available)
#        scripts/install-deps.sh --list                 print the packages, one a line
# bench/run.sh passes the benchmark comparisons' packages as arguments.
# The yardstick is a clean Debian 12 (debootstrap's minbase: scripts/check-clean-machine.sh runs
# both README commands in one), so nothing beyond Debian's required packages is taken for granted:
# not even Debian's own python3 and its venv module, which a Python from pyenv would hide.
set -euo pipefail

packages=(
  python3 python3-venv  # the tests' scripts; the venvs of scripts/bpy-env.sh and scripts/tool-env.sh
  git  # scripts/check-style.sh (the test style.check) reads the changed lines from git
  build-essential patch cmake pkg-config clang libclang-rt-14-dev ccache
  libglm-dev nlohmann-json3-dev libcli11-dev libgtest-dev libfreetype-dev fonts-dejavu-core
  libboost-dev  # headers only: OpenVDB's, built statically by scripts/build-deps.sh with its other libraries
  debootstrap   # tests/cleanroom: the add-on's library loaded in a minimal Debian root
  blender  # the bake tests load the VDB files and meshes in the real Blender (tests/blender)
  xvfb xauth glslang-tools  # the add-on's preview in a real Blender window (xvfb-run); its GLSL checked
  libegl1 libgl1-mesa-dri mesa-vulkan-drivers  # the bpy wheels 5.2+ draw the preview without a window: EGL and Vulkan on Mesa's llvmpipe and lavapipe
  python3-openvdb python3-numpy  # tests/cli/pyopenvdb_test.py: a bake read by Debian's own OpenVDB
  povray  # tests/povray evaluate dqjulia.inc and render generated scenes in the real POV-Ray 3.7
  clang-format clang-tidy  # scripts/check-style.sh (the test style.check); ruff comes from scripts/tool-env.sh ruff
  slurm-wlm munge  # tests/farm: a one-node Slurm cluster on localhost runs a frame array and a tiled bake
  g++-mingw-w64-x86-64-posix wine64  # the Windows build (scripts/build-windows.sh) and its tests under Wine
)
if [ "${1:-}" = --list ]; then
  printf '%s\n' "${packages[@]}"
  exit 0
fi
packages+=("$@")

missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "dqjulia: installing ${missing[*]}" >&2
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "dqjulia: run as root or install sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -q
$sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
