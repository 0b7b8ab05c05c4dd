#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for tests/farm and for trying `dqjulia farm slurm`
# by hand: munged and Slurm 22.05's slurmctld and slurmd (Debian's slurm-wlm and munge, which
# scripts/install-deps.sh installs), with no systemd, cgroups or accounting. Everything it
# makes stays in folders of its own, so it never touches a real cluster's files: Slurm's
# configuration, state, spool and logs in DIR (Slurm runs as root), munged's key, socket and log in
# a private folder under /run owned by the munge user (munged runs as munge, which may not reach
# DIR: a checkout in a home of mode 0700, say), named in DIR/munge.dir, its log copied into DIR at
# stop. The daemons are stopped by the PIDs it recorded.
#
#   scripts/slurm-local.sh start DIR   start the daemons (about a second), wait until the node is idle,
#                                      print `export SLURM_CONF=DIR/slurm.conf` for the client commands
#   scripts/slurm-local.sh stop DIR    stop them (by their PIDs) and wait until they are gone
#
# As root (munged runs as the munge user, Slurm as root). Settings found to work without systemd:
# ProctrackType=proctrack/linuxproc, TaskPlugin=task/none, select/cons_tres with CR_Core,
# SlurmctldHost=<hostname -s>(127.0.0.1); the ports are free ones picked at start.
set -euo pipefail

usage() { echo "usage: slurm-local.sh start|stop DIR" >&2; exit 2; }
[ $# -eq 2 ] || usage
action=$1
dir=$(realpath -m "$2")

stop_pid_file() {  # stop_pid_file FILE: SIGTERM the PID it names, wait up to 10 s for it to end
  local file=$1 pid
  [ -s "$file" ] || return 0
  pid=$(cat "$file")
  if kill -0 "$pid" 2>/dev/null; then
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$pid" 2>/dev/null && kill -KILL "$pid" 2>/dev/null || true
  fi
  rm -f "$file"
}

remove_munge_dir() {  # the private folder of munged named in DIR/munge.dir (its log kept in DIR)
  local munge_dir
  munge_dir=$(cat "$dir/munge.dir" 2>/dev/null || true)
  case "$munge_dir" in
    /run/dqjulia-munge.*)
      cp "$munge_dir/munged.log" "$dir/munged.log" 2>/dev/null || true
      rm -rf "$munge_dir" ;;
  esac
  rm -f "$dir/munge.dir"
}

if [ "$action" = stop ]; then
  stop_pid_file "$dir/slurmd.pid"
  stop_pid_file "$dir/slurmctld.pid"
  stop_pid_file "$dir/munged.pid"
  remove_munge_dir
  exit 0
fi
[ "$action" = start ] || usage

for tool in munged mungekey slurmctld slurmd sinfo; do
  command -v "$tool" >/dev/null || { echo "slurm-local.sh: $tool is missing (scripts/install-deps.sh installs slurm-wlm and munge)" >&2; exit 3; }
done
id munge >/dev/null 2>&1 || { echo "slurm-local.sh: there is no munge user (install the munge package)" >&2; exit 3; }

mkdir -p "$dir"/{state,spool}
remove_munge_dir  # one left by a start that was never stopped
munge=$(mktemp -d /run/dqjulia-munge.XXXXXX)
echo "$munge" > "$dir/munge.dir"
chown munge: "$munge"
chmod 755 "$munge"  # the socket must be reachable; the key itself is 0600
host=$(hostname -s)
free_port() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
ctld_port=$(free_port)
slurmd_port=$(free_port)
while [ "$slurmd_port" = "$ctld_port" ]; do slurmd_port=$(free_port); done
memory=$(awk '/MemTotal/ {print int($2 / 1024 / 2)}' /proc/meminfo)

# munged with its own key and socket in its folder, as the munge user.
runuser -u munge -- mungekey --create --keyfile="$munge/munge.key"
runuser -u munge -- munged --socket="$munge/munge.socket" --key-file="$munge/munge.key" \
  --pid-file="$munge/munged.pid" --log-file="$munge/munged.log" --seed-file="$munge/munged.seed"
cp "$munge/munged.pid" "$dir/munged.pid"

cat > "$dir/slurm.conf" <<EOF
# Written by scripts/slurm-local.sh: a one-node cluster in $dir.
ClusterName=dqjulia-local
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
AuthType=auth/munge
AuthInfo=socket=$munge/munge.socket
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$memory State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$dir/slurm.conf"
slurmctld -i
slurmd

for _ in $(seq 150); do
  state=$(sinfo -h -o %T 2>/dev/null || true)
  [ "$state" = idle ] && { echo "export SLURM_CONF=$SLURM_CONF"; exit 0; }
  sleep 0.2
done
echo "slurm-local.sh: the node did not become idle (state: ${state:-none}); logs in $dir" >&2
tail -5 "$dir/slurmctld.log" "$dir/slurmd.log" >&2 || true
exit 1
