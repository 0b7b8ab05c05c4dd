#!/usr/bin/env bash
# Renders the POV-Ray examples and prints a table of their times (docs/povray.md's table).
#
#   examples/povray/render-all.sh [OUT_DIR]     (default out/povray; build dqjulia first: build/bin/dqjulia)
#
# 1. the hand-written scenes in this folder, which use povray/dqjulia.inc directly;
# 2. scenes written by `dqjulia povray` from the paper's parameter files (examples/*.json);
# 3. a heavy setting (N = 200) drawn through the distance estimate and through a baked DF3 grid.
# Times are wall-clock seconds on this machine, with POV-Ray's own CPU seconds (all threads).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="${1:-$root/out/povray}"
dqjulia="${DQJULIA:-$root/build/bin/dqjulia}"
mkdir -p "$out"
command -v povray >/dev/null || { echo "render-all.sh: povray is not installed (scripts/install-deps.sh)" >&2; exit 1; }
[ -x "$dqjulia" ] || { echo "render-all.sh: $dqjulia not found; build first or set DQJULIA" >&2; exit 1; }

rows=()
# seconds START_NS END_NS: the difference in seconds, one decimal.
seconds() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", (b - a) / 1e9 }'; }
# render NAME SCENE FLAGS... : renders SCENE into $out/NAME.png, records wall and CPU seconds.
render() {
  local name="$1" scene="$2"
  shift 2
  local log="$out/$name.log" start end
  start=$(date +%s%N)
  (cd "$(dirname "$scene")" && povray -D +L"$root/povray" "$@" +I"$(basename "$scene")" +O"$out/$name.png") > "$log" 2>&1 ||
    { echo "render-all.sh: $name failed, see $log" >&2; exit 1; }
  end=$(date +%s%N)
  local cpu parse
  cpu=$(grep -A1 "Trace Time" "$log" | grep -o "with [0-9.]* CPU" | grep -o "[0-9.]*" || echo "?")
  parse=$(grep "Parse Time" "$log" | grep -o "([0-9.]* seconds)" | grep -o "[0-9.]*" || echo "?")
  rows+=("| $name | $* | $(seconds "$start" "$end") | $cpu | $parse |")
  echo "rendered $name" >&2
}

# 1. Hand-written scenes.
render paper-highres "$here/paper-highres.pov" +W640 +H480 +A0.3
render paper-level-of-detail "$here/paper-level-of-detail.pov" +W1280 +H400 +A0.3
render paper-test2 "$here/paper-test2.pov" +W1200 +H800 +A0.3
render materials "$here/materials.pov" +W960 +H400 +A0.3

# 2. Scenes written by `dqjulia povray` from the paper's parameter files (640 x 480, as `dqjulia render`).
for example in paper-highres paper-test2-2 paper-test2-6; do
  "$dqjulia" povray -q -f -p "$root/examples/$example.json" -o "$out/$example-generated.pov"
  render "$example-generated" "$out/$example-generated.pov" +W640 +H480 -A File_Gamma=sRGB
done

# 3. A heavy setting: N = 200, through the function and through a 256^3 DF3 grid.
bake_start=$(date +%s%N)
"$dqjulia" povray -q -f -p "$root/examples/paper-highres.json" -n 200 --df3 --df3-resolution 256 -o "$out/highres-n200.pov"
bake_end=$(date +%s%N)
render highres-n200 "$out/highres-n200.pov" +W640 +H480 -A File_Gamma=sRGB
render highres-n200-df3 "$out/highres-n200_df3.pov" +W640 +H480 -A File_Gamma=sRGB
rows+=("| (baking highres-n200.df3, 256^3, \`dqjulia povray --df3\`) | | $(seconds "$bake_start" "$bake_end") | | |")

echo "| scene | povray flags | wall s | POV-Ray CPU s | parse s |"
echo "|---|---|---|---|---|"
printf '%s\n' "${rows[@]}"
