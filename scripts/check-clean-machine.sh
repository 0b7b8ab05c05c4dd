#!/usr/bin/env bash
# Runs the README's two commands on a clean Debian 12, as a new user would: a fresh copy of
# Debian's minbase root (scripts/debian-root.sh bookworm: Debian's required packages and apt, no
# python3, no pyenv, no caches), this checkout's HEAD cloned into the root user's home (/root, mode
# 0700), then inside it (scripts/in-root.sh: its own /proc, /dev, /run, no variable of this
# machine's) `scripts/quickstart.sh`, then the test command `scripts/test.sh` with CI=true (a
# missing tool fails instead of skipping), each timed. Everything the two commands need must come
# from the project's own scripts.
#
#   scripts/check-clean-machine.sh [--work DIR] [--keep] [--tests COMMAND]
#
#   --work DIR       where the machine's root is made (default: a new folder in /var/tmp); it needs
#                    about 20 GB: the packages, the third-party builds, the bpy venvs, three builds
#   --keep           keep the root afterwards (by default it is deleted, pass or fail)
#   --tests COMMAND  run COMMAND in the checkout instead of scripts/test.sh (say, a quicker
#                    `ctest --test-dir build -L library` after the quickstart)
#
# The commit tested is HEAD (uncommitted changes are not in it), checked out as `main`, as CI's
# clone is. On 2 cores: about 14 minutes for the quickstart, 39 for the tests, more on a busy
# machine (run it with nice). Exit status: 0 if both commands passed. As root.
set -euo pipefail
cd "$(dirname "$0")/.."
checkout=$PWD

work="" keep=0 tests="scripts/test.sh"
while [ $# -gt 0 ]; do
  case "$1" in
    --work) work=${2:?--work needs a folder}; shift 2 ;;
    --keep) keep=1; shift ;;
    --tests) tests=${2:?--tests needs a command}; shift 2 ;;
    *) echo "usage: check-clean-machine.sh [--work DIR] [--keep] [--tests COMMAND]" >&2; exit 2 ;;
  esac
done
[ "$(id -u)" -eq 0 ] || { echo "check-clean-machine.sh: needs root (debootstrap, chroot)" >&2; exit 2; }

base=$(scripts/debian-root.sh bookworm)
if [ -z "$work" ]; then
  work=$(mktemp -d /var/tmp/dqjulia-clean-machine.XXXXXX)
else
  mkdir -p "$work"
  work=$(realpath "$work")
fi
root="$work/root"
[ ! -e "$root" ] || { echo "check-clean-machine.sh: $root exists already" >&2; exit 2; }
cleanup() {
  if [ "$keep" = 1 ]; then
    echo "check-clean-machine.sh: the machine is kept in $root (logs: $work/*.log)" >&2
  else
    rm -rf "$root"
  fi
}
trap cleanup EXIT

started=$SECONDS
cp -a "$base" "$root"
commit=$(git rev-parse HEAD)
git clone -q --no-hardlinks "$checkout" "$root/root/dqjulia"
git -C "$root/root/dqjulia" checkout -q -B main "$commit"
chmod 0700 "$root/root"
echo "check-clean-machine.sh: a fresh Debian 12 minbase root in $root ($(cut -d= -f2 <<<"$(grep ^mirror= "$root/etc/dqjulia-root")"))," \
     "this checkout's $(git rev-parse --short HEAD) in its /root/dqjulia (/root mode $(stat -c %a "$root/root")), in $((SECONDS - started)) s"
# The network, not the machine: where this machine reaches PyPI through a proxy that signs TLS
# with its own authority (pip told so by PIP_CERT or SSL_CERT_FILE), the root is on the same
# network and is told the same, in Debian's site-wide /etc/pip.conf. On an open network nothing
# is added.
network_ca=${PIP_CERT:-${SSL_CERT_FILE:-}}
if [ -n "$network_ca" ] && [ -f "$network_ca" ]; then
  cp "$network_ca" "$root/etc/dqjulia-network-ca.crt"
  printf '[global]\ncert = /etc/dqjulia-network-ca.crt\n' > "$root/etc/pip.conf"
  echo "check-clean-machine.sh: this network's certificate authorities ($network_ca) given to pip in the root (/etc/pip.conf)"
fi
python=$(chroot "$root" /bin/sh -c 'command -v python3 pyenv || true')
echo "check-clean-machine.sh: python3 or pyenv before the quickstart: ${python:-none}"

minutes() { printf '%d min %02d s' $(($1 / 60)) $(($1 % 60)); }
step() {  # step NAME COMMAND: run COMMAND in the checkout inside the root, log it, time it
  local name=$1 command=$2 status=0 begun=$SECONDS
  echo "check-clean-machine.sh: $name: $command (log: $work/$name.log)"
  scripts/in-root.sh "$root" --env CI=true -- /bin/bash -c "cd /root/dqjulia && $command" >"$work/$name.log" 2>&1 ||
    status=$?
  local took=$((SECONDS - begun))
  if [ "$status" -ne 0 ]; then
    tail -40 "$work/$name.log" >&2
    echo "check-clean-machine.sh: $name FAILED (exit $status) after $(minutes $took) (log: $work/$name.log)" >&2
    keep=1
    exit 1
  fi
  echo "check-clean-machine.sh: $name passed in $(minutes $took) ($took s)"
  grep -E '^[0-9]+% tests passed|tests failed out of' "$work/$name.log" || true
}
step quickstart scripts/quickstart.sh
echo "check-clean-machine.sh: Python in the root after the quickstart: $(chroot "$root" /bin/sh -c 'readlink -f "$(command -v python3)"; python3 --version') (pyenv: $(chroot "$root" /bin/sh -c 'command -v pyenv || echo none'))"
step tests "$tests"
echo "check-clean-machine.sh: both commands passed on a clean Debian 12 from /root/dqjulia in $(minutes $((SECONDS - started)))"
