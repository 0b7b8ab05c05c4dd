#!/usr/bin/env bash
# Installs the Debian packages dqjulia needs to build and test, if any are missing.
# Usage: scripts/install-deps.sh [--build|--windows] [MORE PACKAGES...]   (as root, or with sudo)
#        scripts/install-deps.sh --list [--build|--windows]                print them, one a line
#   (no group)  every package: building, the Windows cross build and the tests (scripts/test.sh)
#   --build     building the library, the command and the add-on zip (scripts/quickstart.sh)
#   --windows   --build and the MinGW-w64 cross compiler (scripts/build-windows.sh)
# bench/run.sh passes the benchmark comparisons' packages as arguments.
# The yardstick is a clean Debian 12 (debootstrap's minbase: scripts/check-clean-machine.sh runs
# both README commands in one), so nothing beyond Debian's required packages is taken for granted:
# not even Debian's own python3 and its venv module, which a Python from pyenv would hide.
set -euo pipefail

build_packages=(
  python3 python3-venv  # the build's scripts; the venvs of scripts/bpy-env.sh and scripts/tool-env.sh
  git  # scripts/check-style.sh (the test style.check) reads the changed lines from git
  build-essential patch cmake pkg-config ccache
  libglm-dev nlohmann-json3-dev libcli11-dev libgtest-dev libfreetype-dev fonts-dejavu-core
  libboost-dev  # headers only: OpenVDB's, built statically by scripts/build-deps.sh with its other libraries
)
windows_packages=(
  g++-mingw-w64-x86-64-posix  # the Windows build (scripts/build-windows.sh)
)
test_packages=(
  clang libclang-rt-14-dev  # the sanitizer and fuzzing build (scripts/test.sh)
  debootstrap   # tests/cleanroom: the add-on's library loaded in a minimal Debian root
  blender  # the bake tests load the VDB files and meshes in the real Blender (tests/blender)
  xvfb xauth glslang-tools  # the add-on's preview in a real Blender window (xvfb-run); its GLSL checked
  libegl1 libgl1-mesa-dri mesa-vulkan-drivers  # the bpy wheels 5.2+ draw the preview without a window: EGL and Vulkan on Mesa's llvmpipe and lavapipe
  python3-openvdb python3-numpy  # tests/cli/pyopenvdb_test.py: a bake read by Debian's own OpenVDB
  povray  # tests/povray evaluate dqjulia.inc and render generated scenes in the real POV-Ray 3.7
  optipng  # docs/make-pictures.sh makes the pictures smaller without loss (docs.pictures runs its quick step)
  clang-format clang-tidy  # scripts/check-style.sh (the test style.check); ruff comes from scripts/tool-env.sh ruff
  slurm-wlm munge  # tests/farm: a one-node Slurm cluster on localhost runs a frame array and a tiled bake
  wine64  # the Windows build's tests (tests/windows)
)
list=0
if [ "${1:-}" = --list ]; then
  list=1
  shift
fi
case "${1:-}" in
  --build) packages=("${build_packages[@]}"); shift ;;
  --windows) packages=("${build_packages[@]}" "${windows_packages[@]}"); shift ;;
  *) packages=("${build_packages[@]}" "${windows_packages[@]}" "${test_packages[@]}") ;;
esac
if [ "$list" = 1 ]; then
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
