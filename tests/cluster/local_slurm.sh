#!/usr/bin/env bash
# A throwaway one-node Slurm cluster (munged, slurmctld, slurmd on localhost)
# for the cluster tests:
#   local_slurm.sh start DIR    then `source DIR/env` to point the Slurm commands at it
#   local_slurm.sh stop DIR     safe to call twice, or after a failed start
# Key, config, sockets, state and logs all live in DIR; the ports are picked at
# random among free ones, so it does not clash with a real cluster's daemons.
# Exits 77 (CTest's skip code) where it cannot run: not root, or no Slurm/munge.
set -Eeuo pipefail

usage() { echo "usage: $0 start|stop DIR" >&2; exit 2; }
[[ $# -eq 2 ]] || usage
cmd=$1
mkdir -p "$2"
dir=$(cd "$2" && pwd)
conf=$dir/slurm.conf
socket=$dir/munge.socket

# The pid in a pid file, if that process runs and is this cluster's daemon (its
# command line names DIR; a stale file's pid may belong to another process now).
alive() {
  local pid cmd
  pid=$(cat "$1" 2> /dev/null) && [[ -n $pid ]] || return 1
  cmd=$({ tr '\0' ' ' < "/proc/$pid/cmdline"; } 2> /dev/null) || return 1
  [[ $cmd == *"$dir/"* ]] && echo "$pid"
}

logs() {
  local f
  for f in "$dir"/munged.log "$dir"/slurmctld.log "$dir"/slurmd.log; do
    [[ -f $f ]] || continue
    echo "---- $f (last 40 lines)"
    tail -n 40 "$f"
  done
}

# Processes of this cluster that outlived their pid file or a shutdown, found by
# what ties them to DIR, never by a process name alone: the daemons are started
# with BLVD_LOCAL_SLURM=DIR in their environment; slurmstepd (which gets a clean
# environment) runs in slurmd's working directory, DIR.
stragglers() {
  local p exe env
  for p in /proc/[0-9]*; do
    env=$({ tr '\0' '\n' < "$p/environ"; } 2> /dev/null || true)
    if [[ $'\n'$env$'\n' == *$'\n'"BLVD_LOCAL_SLURM=$dir"$'\n'* ]]; then
      echo "${p#/proc/}"
    elif exe=$(readlink "$p/exe" 2> /dev/null) && [[ ${exe##*/} == slurmstepd ]] &&
      [[ $(readlink "$p/cwd" 2> /dev/null) == "$dir" ]]; then
      echo "${p#/proc/}"
    fi
  done
  return 0
}

stop() {
  local pid
  if alive "$dir/slurmctld.pid" > /dev/null; then
    export SLURM_CONF=$conf
    # Jobs first: `scontrol shutdown` stops the daemons but leaves running job
    # steps (slurmstepd and the job's processes) behind.
    local jobs
    jobs=$(timeout 10 squeue -h -o %A 2> /dev/null | sort -u || true)
    if [[ -n $jobs ]]; then
      # shellcheck disable=SC2086
      timeout 10 scancel $jobs 2> /dev/null || true
      for _ in $(seq 50); do
        [[ -z $(timeout 10 squeue -h -o %A 2> /dev/null || true) ]] && break
        sleep 0.2
      done
    fi
    timeout 10 scontrol shutdown > /dev/null 2>&1 || true
  fi
  local f
  for f in slurmd slurmctld; do
    for _ in $(seq 50); do alive "$dir/$f.pid" > /dev/null || break; sleep 0.2; done
    if pid=$(alive "$dir/$f.pid"); then kill -KILL "$pid" 2> /dev/null || true; fi
  done
  if pid=$(alive "$dir/munged.pid"); then
    munged -s --socket="$socket" > /dev/null 2>&1 || kill "$pid" 2> /dev/null || true
    for _ in $(seq 50); do alive "$dir/munged.pid" > /dev/null || break; sleep 0.2; done
    if pid=$(alive "$dir/munged.pid"); then kill -KILL "$pid" 2> /dev/null || true; fi
  fi
  local left
  left=$(stragglers)
  if [[ -n $left ]]; then
    # shellcheck disable=SC2086
    kill -KILL $left 2> /dev/null || true
  fi
  rm -f "$dir"/*.pid
}

port_free() {
  if command -v ss > /dev/null; then
    local used
    used=$(ss -Htan | awk '{print $4}')
    [[ $'\n'$used$'\n' != *":$1"$'\n'* ]]
  else
    if (exec 3<> "/dev/tcp/127.0.0.1/$1") 2> /dev/null; then return 1; fi
  fi
}

free_port() {
  local p
  for _ in $(seq 100); do
    p=$((20000 + RANDOM % 20000))
    if port_free "$p" && [[ $p != "${1:-}" ]]; then echo "$p"; return; fi
  done
  echo "local_slurm: no free port found in 20000-40000" >&2
  return 1
}

start() {
  if [[ $(id -u) -ne 0 ]]; then
    # slurmd must start jobs as their user, and munged/slurmctld here run as root.
    echo "local_slurm: skipped: needs root (a one-node cluster runs its daemons as root)"
    exit 77
  fi
  local t
  for t in munged slurmctld slurmd sbatch scontrol scancel squeue sinfo; do
    if ! command -v "$t" > /dev/null; then
      echo "local_slurm: skipped: $t not found (Slurm and munge: packaging/scripts/deps.sh)"
      exit 77
    fi
  done
  # A Unix socket path is at most 107 bytes.
  if ((${#socket} > 100)); then
    echo "local_slurm: $dir is too deep for a Unix socket path; use a shorter DIR" >&2
    exit 1
  fi

  stop  # whatever an earlier run left in DIR
  # A fresh controller state: otherwise slurmctld recovers the jobs of an earlier run.
  rm -rf "$dir/state" "$dir/spool" "$dir"/*.log "$dir/munge.key"
  mkdir -p "$dir/state" "$dir/spool"
  trap 'echo "local_slurm: start failed" >&2; logs >&2; stop' ERR

  dd if=/dev/urandom of="$dir/munge.key" bs=1024 count=1 status=none
  chmod 400 "$dir/munge.key"
  BLVD_LOCAL_SLURM=$dir munged -f --socket="$socket" --key-file="$dir/munge.key" --log-file="$dir/munged.log" \
    --pid-file="$dir/munged.pid" --seed-file="$dir/munged.seed"

  local ctld_port slurmd_port
  ctld_port=$(free_port)
  slurmd_port=$(free_port "$ctld_port")
  cat > "$conf" << EOF
# One-node test cluster written by tests/cluster/local_slurm.sh.
ClusterName=blvdtest
SlurmctldHost=localhost
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/pgid
TaskPlugin=task/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
MpiDefault=none
ReturnToService=2
# A cancelled job gets SIGKILL 5 s after SIGTERM (default 30 s).
KillWait=5
# sbatch --wait polls every 2 s only while that is under MinJobAge/2; with the
# default 300 s it sleeps 2, 8, then 32 s between polls, which would make the
# tests wait half a minute for a job that has ended.
MinJobAge=5
NodeName=localhost NodeHostname=localhost CPUs=$(nproc) State=UNKNOWN
PartitionName=blvd Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
  printf 'export SLURM_CONF=%q\n' "$conf" > "$dir/env"

  export SLURM_CONF=$conf
  BLVD_LOCAL_SLURM=$dir slurmctld -f "$conf"
  BLVD_LOCAL_SLURM=$dir slurmd -f "$conf" -N localhost

  local state=
  for _ in $(seq 150); do
    state=$(sinfo -h -o %t 2> /dev/null || true)
    [[ $state == idle ]] && break
    sleep 0.2
  done
  if [[ $state != idle ]]; then
    echo "local_slurm: the node is not idle after 30 s (sinfo: '${state}')" >&2
    false
  fi
  trap - ERR
  echo "local_slurm: one-node cluster up in $dir (slurmctld port $ctld_port, slurmd port $slurmd_port)"
}

case $cmd in
  start) start ;;
  stop) stop ;;
  *) usage ;;
esac
