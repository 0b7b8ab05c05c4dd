#!/usr/bin/env bash
# A minimal Debian root, made once and cached outside the checkout: Debian's minbase (what
# debootstrap --variant=minbase installs: the required packages and apt) plus the packages asked
# for (installed by apt inside, without recommends). Prints the root's path.
#
#   scripts/debian-root.sh SUITE [--with PKG...]     SUITE: bullseye (11), bookworm (12), trixie (13)
#
# The roots live in ${DQJ_ROOTS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/roots}/<suite>-<key>,
# the key naming the recipe and the package list (sorted), so each list has its own root: the
# suite's minbase root is made once by debootstrap (about 2 minutes, 160 MB), one with packages
# from a copy of it by apt inside. A root is made in a temporary folder beside its place and
# renamed into place when complete; two callers at once wait for one another (flock) and share
# it. It is only a cache: delete it and it is made again. The Debian mirror is this machine's (its
# apt sources), or $DQJ_DEBIAN_MIRROR. Run what is inside with scripts/in-root.sh ROOT COMMAND...,
# which mounts /proc, /dev and the rest. As root.
set -euo pipefail

recipe=r1  # bump when the way roots are made changes: every cached root is made again
usage() { echo "usage: debian-root.sh bullseye|bookworm|trixie [--with PKG...]" >&2; exit 2; }
[ $# -ge 1 ] || usage
suite=$1
shift
case "$suite" in bullseye | bookworm | trixie) ;; *) usage ;; esac
packages=()
if [ $# -gt 0 ]; then
  [ "$1" = --with ] || usage
  shift
  for package in "$@"; do
    [[ "$package" =~ ^[a-z0-9][a-z0-9+.-]*$ ]] || { echo "debian-root.sh: not a package name: '$package'" >&2; exit 2; }
  done
  mapfile -t packages < <(printf '%s\n' "$@" | sort -u)
fi
[ "$(id -u)" -eq 0 ] || { echo "debian-root.sh: needs root (debootstrap, chroot)" >&2; exit 2; }
command -v debootstrap >/dev/null || { echo "debian-root.sh: debootstrap is missing (scripts/install-deps.sh installs it)" >&2; exit 3; }

mirror() {  # the Debian mirror this machine's apt uses (not the security one)
  [ -n "${DQJ_DEBIAN_MIRROR:-}" ] && { echo "$DQJ_DEBIAN_MIRROR"; return; }
  local url
  url=$(sed -nE 's/^[[:space:]]*(URIs:|deb)[[:space:]]+(\[[^]]*\][[:space:]]+)?(\S+).*/\3/p' \
          /etc/apt/sources.list.d/*.sources /etc/apt/sources.list.d/*.list /etc/apt/sources.list 2>/dev/null |
        grep -E '/debian/?$' | grep -v security | head -1 || true)
  echo "${url:-http://deb.debian.org/debian}"
}

cache="${DQJ_ROOTS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/dqjulia/roots}"
if [ ${#packages[@]} -eq 0 ]; then
  key=minbase
else
  key=$(IFS=+; echo "${packages[*]}")
  [ ${#key} -le 64 ] || key=$(printf '%s\n' "${packages[@]}" | sha256sum | cut -c1-16)
fi
root="$cache/$suite-$recipe-$key"
mkdir -p "$cache"
exec 9>"$cache/.$suite-$recipe-$key.lock"
flock 9
if [ -d "$root" ]; then
  echo "$root"
  exit 0
fi

started=$SECONDS
echo "debian-root.sh: making $root (debootstrap --variant=minbase $suite${packages[*]:+, then ${packages[*]}})" >&2
work=$(mktemp -d "$cache/.$suite-$recipe-$key.XXXXXX")
trap 'rm -rf "$work"' EXIT
log="$work/make.log"
if [ ${#packages[@]} -eq 0 ]; then
  if ! debootstrap --variant=minbase "$suite" "$work/root" "$(mirror)" >"$log" 2>&1; then
    tail -20 "$log" >&2
    echo "debian-root.sh: debootstrap $suite failed (log above)" >&2
    exit 1
  fi
else
  # A copy of the suite's minbase root (itself made once), then apt inside.
  base=$("$0" "$suite")
  cp -a "$base" "$work/root"
  # No service starts inside (policy-rc.d), as in any chroot; removed again afterwards.
  printf '#!/bin/sh\nexit 101\n' > "$work/root/usr/sbin/policy-rc.d"
  chmod 755 "$work/root/usr/sbin/policy-rc.d"
  if ! "$(dirname "$0")/in-root.sh" "$work/root" --env DEBIAN_FRONTEND=noninteractive -- /bin/sh -c \
      "apt-get update -q && apt-get install -y -q --no-install-recommends ${packages[*]} && apt-get clean" >"$log" 2>&1; then
    tail -20 "$log" >&2
    echo "debian-root.sh: installing ${packages[*]} in the $suite root failed (log above)" >&2
    exit 1
  fi
  rm -f "$work/root/usr/sbin/policy-rc.d"
fi
rm -rf "$work/root/var/lib/apt/lists/"* "$work/root/var/cache/apt/"*.bin
printf 'suite=%s\nrecipe=%s\npackages=%s\nmirror=%s\n' "$suite" "$recipe" "${packages[*]}" "$(mirror)" \
  > "$work/root/etc/dqjulia-root"
mv "$work/root" "$root"
echo "debian-root.sh: made $root in $((SECONDS - started)) s ($(du -sh "$root" | cut -f1))" >&2
echo "$root"
