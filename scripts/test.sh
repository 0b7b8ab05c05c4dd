#!/usr/bin/env bash
# The README's second command: install what is missing, build, and run every test:
# first the Release build and the Windows cross build, then the Release build's tests (among them
# the release tests, which package both builds as scripts/release.sh does), then the Windows
# build's tests under Wine (against the Release build), then the whole suite again built with
# clang under AddressSanitizer and UndefinedBehaviorSanitizer, with the libFuzzer targets run for
# a bounded time.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
# The Python venvs (on a fresh machine about 800 MB of bpy wheels from PyPI: network, not CPU)
# are made while the static third-party libraries compile; the build's configure step looks for
# them, so it waits for both.
venvs_log="$(mktemp)"
trap 'rm -f "$venvs_log"' EXIT
(scripts/bpy-env.sh && scripts/tool-env.sh ruff && scripts/tool-env.sh mypy && scripts/tool-env.sh openjd && scripts/tool-env.sh twine && scripts/tool-env.sh auditwheel) >"$venvs_log" 2>&1 &
venvs=$!
scripts/build-deps.sh >/dev/null
if ! wait "$venvs"; then
  cat "$venvs_log" >&2
  echo "dqjulia: making the Python venvs failed (scripts/bpy-env.sh, scripts/tool-env.sh)" >&2
  exit 1
fi
cat "$venvs_log"
scripts/build.sh
echo "dqjulia: Windows cross build (MinGW-w64)"
scripts/build-windows.sh
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
