#!/usr/bin/env bash
# How POV-Ray's cost grows with the iteration count N (docs/povray.md's table): dqjulia.inc builds
# a chain of N + 2 functions, so parsing and each evaluation should grow linearly in N.
#
#   examples/povray/bench-iterations.sh [N ...]     (default 15 30 60 120 240; build dqjulia first)
#
# For each N: (1) `dqjulia povray -n N` for the default parameters, rendered at 320 x 240
# without anti-aliasing: POV-Ray's parse and trace times; (2) the worst case for the chain,
# 20000 evaluations at a point inside the set (every one runs all N iterations), timed inside
# POV-Ray's parser.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
dqjulia="${DQJULIA:-$root/build/bin/dqjulia}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
levels=("$@")
[ ${#levels[@]} -gt 0 ] || levels=(15 30 60 120 240)

echo "| N | parse s | trace s (wall) | trace CPU s | 20000 inside evaluations s |"
echo "|---|---|---|---|---|"
for n in "${levels[@]}"; do
  "$dqjulia" povray -q -f -n "$n" -W 320 -H 240 -o "$work/n$n.pov"
  (cd "$work" && povray -D +W320 +H240 -A +FN +In$n.pov +On$n.png) > "$work/render.log" 2>&1
  parse=$(grep "Parse Time" "$work/render.log" | grep -o "([0-9.]* seconds)" | grep -o "[0-9.]*")
  trace=$(grep "Trace Time" "$work/render.log" | grep -o "([0-9.]* seconds)" | grep -o "[0-9.]*")
  cpu=$(grep -A1 "Trace Time" "$work/render.log" | grep -o "with [0-9.]* CPU" | grep -o "[0-9.]*")
  cat > "$work/eval$n.pov" <<EOF
#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "dqjulia.inc"
sphere { 0, 1 pigment { rgb 1 } }
#declare C = array[8] {-0.39054, -0.58679, 0, 0, 0, 0.5632, 0, 0.05};
#declare F = DQJ_Distance_Function(C, "paper", $n, 4, DQJ_Slice_Names("a.s,a.i,a.j"));
#declare K = 0;
#while (K < 20000)
  #declare V = F(0.01, 0.1, 0);
  #declare K = K + 1;
#end
EOF
  (cd "$work" && povray -D +W1 +H1 -F +Ieval$n.pov) > "$work/eval.log" 2>&1
  evaluate=$(grep "Parse Time" "$work/eval.log" | grep -o "([0-9.]* seconds)" | grep -o "[0-9.]*")
  echo "| $n | $parse | $trace | $cpu | $evaluate |"
done
