#!/usr/bin/env bash
# The README's second command: install what is missing, build, and run every test:
# first the Release build and the Windows cross build, then the Release build's tests (among them
# the release tests, which package both builds as scripts/release.sh does), then the Windows
# build's tests under Wine (against the Release build), then the whole suite again built with
# clang under AddressSanitizer and UndefinedBehaviorSanitizer, with the libFuzzer targets run for
# a bounded time.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --windows  # what both builds need (after scripts/quickstart.sh: the cross compiler)
# Meanwhile, the tests' packages (Blender, POV-Ray, Wine, Slurm, clang, ...: on a fresh machine a
# few minutes of apt) and the Python venvs (about 800 MB of bpy wheels from PyPI, Sphinx for the
# documentation's tests and, without a CPython 3.13, a Debian 13 root) are installed in the
# background: network and disk more than CPU, beside the builds' compiling. The builds'
# configure steps look for all of them, so when anything was new, both builds are configured
# again once it is there (seconds: nothing recompiles).
# Not as root, sudo may ask for a password, which it cannot in the background: the packages are
# then installed first.
tests_packages=scripts/install-deps.sh
if [ "$(id -u)" -ne 0 ]; then
  scripts/install-deps.sh
  tests_packages=true
fi
background_log="$(mktemp)"
trap 'rm -f "$background_log"' EXIT
("$tests_packages" && scripts/bpy-env.sh && scripts/tool-env.sh ruff && scripts/tool-env.sh mypy && scripts/tool-env.sh openjd && scripts/tool-env.sh twine && scripts/tool-env.sh auditwheel && scripts/tool-env.sh sphinx && scripts/tool-env.sh meshcheck) >"$background_log" 2>&1 &
background=$!
scripts/build-deps.sh >/dev/null
scripts/build.sh
echo "dqjulia: Windows cross build (MinGW-w64)"
scripts/build-windows.sh
if ! wait "$background"; then
  cat "$background_log" >&2
  echo "dqjulia: installing the tests' packages or making the Python venvs failed (scripts/install-deps.sh, scripts/bpy-env.sh, scripts/tool-env.sh)" >&2
  exit 1
fi
cat "$background_log"
if grep -q "dqjulia: installing\|making" "$background_log"; then
  echo "dqjulia: configuring both builds again, now that the new packages and venvs are there"
  scripts/build.sh >/dev/null
  scripts/build-windows.sh >/dev/null
fi
# Label `long` (tiled bakes at farm sizes, minutes) is run by hand: ctest --test-dir build -L long
ctest --test-dir build --output-on-failure -j"$(nproc)" -LE long

echo "dqjulia: the Windows build's tests under Wine"
ctest --test-dir build-windows --output-on-failure -j"$(nproc)"

echo "dqjulia: sanitizer and fuzzing run (clang, ASan + UBSan)"
source scripts/ccache.sh
CC=clang CXX=clang++ cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo -DDQJ_SANITIZE=ON -DDQJ_FUZZ=ON \
  -DDQJ_DEPS_PREFIX="$(scripts/build-deps.sh --print)" "${DQJ_LAUNCHER[@]}" >/dev/null
cmake --build build-sanitize -j"$(nproc)"
# Blender loads the library into its own (uninstrumented) process, where an ASan library cannot run.
ctest --test-dir build-sanitize --output-on-failure -j"$(nproc)" -LE blender
