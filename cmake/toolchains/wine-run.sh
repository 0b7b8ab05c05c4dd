#!/usr/bin/env bash
# Runs a Windows program under Wine, headless, in the Wine prefix given first (the Windows build's
# CMAKE_CROSSCOMPILING_EMULATOR: tests and build steps run the programs they built through it):
#
#   wine-run.sh WINEPREFIX PROGRAM.exe [ARGUMENTS...]     exit status: the program's
#
# Debian's wine64 lives in Wine's library folder (/usr/lib/wine), not on PATH. Wine's own messages
# are off (WINEDEBUG=-all), there is no display (console programs need none), HOME is a scratch
# folder beside the prefix, and Wine's Mono and Gecko installers are skipped. The first run
# creates the prefix (about 10 s), under a lock so that parallel first runs create it once.
set -euo pipefail
prefix=$1
shift
wine=$(command -v wine64 || true)
[ -n "$wine" ] || wine=/usr/lib/wine/wine64
if [ ! -x "$wine" ]; then
  echo "wine-run.sh: wine64 is not installed (scripts/install-deps.sh installs it)" >&2
  exit 127
fi
export WINEPREFIX=$prefix WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml=" HOME="$prefix-home"
unset DISPLAY WAYLAND_DISPLAY
mkdir -p "$HOME"
if [ ! -f "$prefix/system.reg" ]; then
  (
    flock 9
    [ -f "$prefix/system.reg" ] || "$wine" wineboot --init >/dev/null 2>&1
    "$(dirname "$wine")/wineserver" --wait 2>/dev/null || true
  ) 9>"$prefix.lock"
fi
exec "$wine" "$@"
