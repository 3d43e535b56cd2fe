#!/usr/bin/env bash
# A one-node Slurm cluster on localhost, and an ensemble run on it as a job
# array (issue 35): installs Debian's slurm-wlm and munge when missing (not
# part of the README's two commands), starts munged, slurmctld and slurmd as
# plain daemons (no systemd), submits the ensemble's shards as an array
# (one task per shard: pumasim ensemble --shard $SLURM_ARRAY_TASK_ID/N),
# waits for it, merges the shards with pumasim ensemble --merge, checks the
# merge against the table one process writes (every field but wall_time),
# and stops the daemons it started. Its log goes to results/ensembles/slurm_one_node.log.
#
# Usage: scripts/slurm_one_node.sh [ENSEMBLE.toml [N]]
# (default: experiments/ensembles/paper_slow_viscous_drive.toml with 20
# samples at t_end 0.5 s, 4 shards). Needs root (it installs packages and
# writes /etc/slurm/slurm.conf, /etc/munge/munge.key when absent) and the
# release build (scripts/build.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
bin=$root/build/release/bin/pumasim
[ -x "$bin" ] || { echo "slurm_one_node: $bin missing: run scripts/build.sh first" >&2; exit 2; }
[ "$(id -u)" -eq 0 ] || { echo "slurm_one_node: needs root (packages, /etc/slurm, daemons)" >&2; exit 2; }
n=${2:-4}
log=$root/results/ensembles/slurm_one_node.log
work=$(mktemp -d /tmp/pumasim_slurm.XXXXXX)
chmod 755 "$work"
# Pid files of the daemons this script started (a daemon already running is
# left alone). A daemon forks away from the command that starts it, so its
# pid is read from its pid file at cleanup, not taken at start.
started=()
cleanup() {
  for f in "${started[@]}"; do
    [ -s "$f" ] && kill "$(cat "$f")" 2>/dev/null || true
  done
  rm -rf "$work"
}
trap cleanup EXIT
say() { echo "$*" | tee -a "$log.tmp"; }
: > "$log.tmp"

for p in slurm-wlm munge; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm munge
    break
  fi
done
say "# scripts/slurm_one_node.sh on $(hostname), $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores"
say "slurm: $(sinfo --version 2>/dev/null || slurmctld -V), munge: $(munge --version 2>&1 | head -n 1)"

# munge: a key when there is none, then the daemon.
if [ ! -s /etc/munge/munge.key ]; then
  dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key status=none
  chown munge:munge /etc/munge/munge.key && chmod 400 /etc/munge/munge.key
fi
mkdir -p /run/munge && chown munge:munge /run/munge
if ! pgrep -x munged >/dev/null; then
  su -s /bin/sh munge -c /usr/sbin/munged && started+=(/run/munge/munged.pid)
fi

# slurm.conf for this one node, written only when there is none (never
# replacing an administrator's).
host=$(hostname -s)
cpus=$(nproc)
mem=$(awk '/MemTotal/ {print int($2 / 1024) - 512}' /proc/meminfo)
conf=/etc/slurm/slurm.conf
if [ ! -e "$conf" ]; then
  mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd /var/log/slurm
  cat > "$conf" <<CONF
# Written by pumasim's scripts/slurm_one_node.sh: a one-node cluster on localhost.
ClusterName=pumasim
SlurmctldHost=$host
SlurmUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
fi
if ! pgrep -x slurmctld >/dev/null; then
  slurmctld && started+=(/run/slurmctld.pid)
fi
if ! pgrep -x slurmd >/dev/null; then
  slurmd && started+=(/run/slurmd.pid)
fi
for _ in $(seq 60); do
  sinfo -h -o %T 2>/dev/null | grep -qE "idle|mix" && break
  sleep 1
done
say "node: $(sinfo -h -o '%N %c cpus %T')"

# The ensemble: the given file, or the drive ensemble at 20 samples and 0.5 s.
if [ $# -ge 1 ]; then
  ensemble=$(realpath "$1")
else
  ensemble=$work/e.toml
  sed -e 's/^samples = .*/samples = 20/' -e 's/^t_end = .*/t_end = 0.5/' \
      -e "s|^scene = \"\(.*\)\"|scene = \"$root/experiments/ensembles/\1\"|" \
      experiments/ensembles/paper_slow_viscous_drive.toml > "$ensemble"
fi
say "ensemble: $ensemble, $n shards"
start=$SECONDS
job=$(sbatch --parsable --array=1-"$n" --ntasks=1 --cpus-per-task=1 --output="$work/task_%a.out" \
  --wrap="$bin ensemble $ensemble --shard \$SLURM_ARRAY_TASK_ID/$n --threads 1 --out $work/shard\$SLURM_ARRAY_TASK_ID.csv -q")
say "submitted: job array $job (tasks 1-$n)"
for _ in $(seq 600); do
  [ -z "$(squeue -h -j "$job" 2>/dev/null)" ] && break
  sleep 1
done
shards=()
written=0
for k in $(seq "$n"); do
  shards+=("$work/shard$k.csv")
  [ -s "$work/shard$k.csv" ] && written=$((written + 1))
done
say "array finished after $((SECONDS - start)) s: $written of $n tasks wrote their shard's table"
"$bin" ensemble "$ensemble" --merge "${shards[@]}" --out "$work/merged.csv" -q
"$bin" ensemble "$ensemble" --threads 1 --out "$work/whole.csv" -q
same=$(/usr/bin/python3 scripts/same_ensemble_tables.py "$work/whole.csv" "$work/merged.csv")
say "merged: ${same%% samples*} samples from the job array equal the single-process table, every field but wall_time"
mv "$log.tmp" "$log"
echo "slurm_one_node: log in ${log#$root/}"
