#!/usr/bin/env bash
# Runs a command inside a Debian root (a folder made by scripts/debian-root.sh, or a copy of
# one) as a machine of its own would: chrooted, in private mount and PID namespaces, with /proc,
# /sys, /dev (and /dev/pts), a fresh /dev/shm and /run, this machine's DNS settings, and a clean
# environment (no variable of this machine's but TERM; PATH, HOME and LANG as Debian sets them).
#
#   scripts/in-root.sh ROOT [--env NAME=VALUE]... [--] COMMAND [ARGS...]
#
# The mounts belong to the command's namespace: they vanish with it, however it ends, and are
# never seen outside. Daemons the command leaves running (munged, slurmd, Xvfb, wineserver) end
# with it too, since it is PID 1 of its namespace. As root (unshare, mount, chroot need it).
set -euo pipefail

usage() { echo "usage: in-root.sh ROOT [--env NAME=VALUE]... [--] COMMAND [ARGS...]" >&2; exit 2; }
[ $# -ge 2 ] || usage
root=$(realpath "$1")
shift
environment=(TERM="${TERM:-dumb}" HOME=/root LANG=C.UTF-8
             PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin)
while [ $# -gt 0 ]; do
  case "$1" in
    --env) [ $# -ge 2 ] || usage; environment+=("$2"); shift 2 ;;
    --) shift; break ;;
    *) break ;;
  esac
done
[ $# -ge 1 ] || usage
[ -x "$root/bin/sh" ] || { echo "in-root.sh: $root is not a Debian root (no /bin/sh)" >&2; exit 2; }
[ "$(id -u)" -eq 0 ] || { echo "in-root.sh: needs root (unshare, mount, chroot)" >&2; exit 2; }

# Name resolution as on this machine (apt and pip inside need it); localhost and this host's name.
if [ -f /etc/resolv.conf ]; then
  rm -f "$root/etc/resolv.conf"
  cat /etc/resolv.conf > "$root/etc/resolv.conf"
fi
host=$(hostname)
if ! grep -qw "$host" "$root/etc/hosts" 2>/dev/null; then
  printf '127.0.0.1\tlocalhost\n127.0.1.1\t%s\n::1\tlocalhost ip6-localhost ip6-loopback\n' "$host" >> "$root/etc/hosts"
fi

# Inside the new namespaces: mount, then chroot with the clean environment (exec: the command
# becomes the namespace's PID 1's only child and its exit status is ours).
exec unshare --mount --pid --fork --kill-child --propagation private -- /bin/bash -c '
  set -e
  root=$1
  shift
  # The root a mount point of its own, as / is on a machine: a command inside that makes its own
  # namespaces (unshare --propagation, as this script does in a root made inside) needs one.
  mount --bind "$root" "$root"
  mount -t proc proc "$root/proc"
  mount --rbind /sys "$root/sys"
  mount --rbind /dev "$root/dev"
  mount -t tmpfs -o mode=1777,nosuid,nodev shm "$root/dev/shm"
  mount -t tmpfs -o mode=0755,nosuid,nodev run "$root/run"
  mkdir -p "$root/run/lock" && chmod 1777 "$root/run/lock"
  exec chroot "$root" /usr/bin/env -i "$@"
' in-root "$root" "${environment[@]}" "$@"
