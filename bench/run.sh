#!/usr/bin/env bash
# bench/run.sh - the benchmark suite in one command: installs what the comparisons need
# (Google Benchmark, POV-Ray, Mandelbulber 2, GNU time), builds dqjulia in Release with the
# benchmarks into build-bench/, then runs bench/compare.py, which prints the table of
# same-run ratios (docs/performance.md). Extra arguments go to compare.py, e.g.
#   bench/run.sh --skip-mesh --bake-resolutions 256,512
# Not part of the test command: benchmarks are not tests. Takes 15 to 25 minutes on 2 cores (the
# 512^3 meshes, three runs of Mandelbulber 2 on each of two scenes, are about half of it).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh libbenchmark-dev mandelbulber2 time

scripts/build-deps.sh >/dev/null  # the static third-party libraries (cached)
cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release -DDQJ_BUILD_BENCH=ON -DDQJ_BUILD_TESTS=OFF >/dev/null
cmake --build build-bench -j"$(nproc)" --target dqjulia_cli dqjulia_bench
exec /usr/bin/python3 bench/compare.py --build build-bench "$@"
