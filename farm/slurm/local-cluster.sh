#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, in one folder, for trying farm/slurm/render.sbatch
# and for its test (tests/farm_slurm.rs): munged, slurmctld and slurmd on 127.0.0.1 with a
# minimal slurm.conf, everything (key, sockets, state, logs) under DIR, nothing under /etc.
#
#   farm/slurm/local-cluster.sh start DIR   # prints `export SLURM_CONF=DIR/slurm.conf`
#   SLURM_CONF=DIR/slurm.conf sbatch --wait --array=1-3 farm/slurm/render.sbatch SCENE OUT
#   farm/slurm/local-cluster.sh stop DIR
#
# Runs as root (slurmd starts jobs as their user) with Debian's `slurmd`, `slurmctld`,
# `slurm-client` and `munge` (scripts/ensure-slurm.sh installs them). The node declares two
# GPUs as generic resources (GRES, counted only: no device files), so a job script's
# `--gres=gpu:1` is accepted and limits the node to two such tasks at once, as on a GPU node.
# Ports: SLURMCTLD_PORT and SLURMD_PORT, else two picked at random, so that several clusters
# (several test runs) can live side by side. `start` waits until the node is idle and fails,
# printing the daemons' logs, when a daemon does not come up; it stops what it started then.
set -euo pipefail

usage() {
    echo "usage: $0 start|stop DIR" >&2
    exit 2
}
[ $# -eq 2 ] || usage
cmd=$1
dir=$(mkdir -p "$2" && cd "$2" && pwd)

# Prints every daemon log under DIR (the reason a start failed).
logs() {
    for f in "$dir"/munged.log "$dir"/slurmctld.log "$dir"/slurmd.log; do
        if [ -f "$f" ]; then
            echo "---- $f (last 40 lines)" >&2
            tail -n 40 "$f" >&2
        fi
    done
}

# Stops the daemons whose pid files are under DIR (slurmd first, munged last), waiting up to
# 10 s for each to exit.
stop() {
    local name pid
    for name in slurmd slurmctld munged; do
        [ -f "$dir/$name.pid" ] || continue
        pid=$(cat "$dir/$name.pid")
        if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null; then
            kill "$pid" 2>/dev/null || true
            for _ in $(seq 100); do
                kill -0 "$pid" 2>/dev/null || break
                sleep 0.1
            done
            if kill -0 "$pid" 2>/dev/null; then
                kill -9 "$pid" 2>/dev/null || true
            fi
        fi
        rm -f "$dir/$name.pid"
    done
}

fail() {
    echo "local-cluster: $*" >&2
    logs
    stop
    exit 1
}

case $cmd in
stop)
    stop
    exit 0
    ;;
start) ;;
*) usage ;;
esac

[ "$(id -u)" = 0 ] || fail "must run as root (slurmd starts each job as its user)"
for tool in munged mungekey slurmctld slurmd sbatch sinfo scontrol; do
    command -v "$tool" >/dev/null ||
        fail "$tool is not installed (scripts/ensure-slurm.sh installs slurmd, slurmctld, slurm-client and munge)"
done

ctld_port=${SLURMCTLD_PORT:-$(shuf -i 20000-40000 -n 1)}
slurmd_port=${SLURMD_PORT:-$(shuf -i 40001-60000 -n 1)}
cpus=$(nproc)
mem=$(awk '/MemTotal/ { print int($2 / 1024 / 2) }' /proc/meminfo)
mkdir -p "$dir/state" "$dir/spool"
chmod 700 "$dir"

# munge: a private key and socket; the Slurm daemons and commands find it through AuthInfo.
rm -f "$dir/munge.key"
mungekey --create --keyfile="$dir/munge.key" >/dev/null 2>&1 ||
    dd if=/dev/urandom of="$dir/munge.key" bs=1024 count=1 status=none
chmod 400 "$dir/munge.key"
munged --force --socket="$dir/munge.socket" --key-file="$dir/munge.key" \
    --pid-file="$dir/munged.pid" --log-file="$dir/munged.log" --seed-file="$dir/munged.seed" \
    >>"$dir/munged.log" 2>&1 || fail "munged did not start"
# A socket within 30 s (it comes at once on an idle machine; CI's are busy).
for _ in $(seq 300); do
    [ -S "$dir/munge.socket" ] && break
    sleep 0.1
done
[ -S "$dir/munge.socket" ] || fail "munged made no socket at $dir/munge.socket"

cat >"$dir/slurm.conf" <<EOF
# A one-node cluster for farm/slurm/render.sbatch (farm/slurm/local-cluster.sh).
ClusterName=reyesfarm
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# No cgroups in a container: processes are tracked by their parent ids.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MailProg=/bin/true
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
KillWait=5
GresTypes=gpu
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem Gres=gpu:2 State=UNKNOWN
PartitionName=farm Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
# Two GPUs counted: Slurm drops a GPU without a device file, so two empty files stand for
# /dev/nvidia0 and /dev/nvidia1 (without task/cgroup nothing opens or fences them).
mkdir -p "$dir/dev"
touch "$dir/dev/gpu0" "$dir/dev/gpu1"
printf 'AutoDetect=off\nName=gpu File=%s/dev/gpu[0-1]\n' "$dir" >"$dir/gres.conf"
export SLURM_CONF=$dir/slurm.conf

slurmctld -f "$SLURM_CONF" -i >>"$dir/slurmctld.log" 2>&1 || fail "slurmctld did not start"
slurmd -f "$SLURM_CONF" -N localhost >>"$dir/slurmd.log" 2>&1 || fail "slurmd did not start"

# The node registers within a few seconds; 2 minutes (on a busy machine) is a daemon that will
# not come up.
state=
for _ in $(seq 600); do
    state=$(sinfo --noheader --nodes=localhost --format=%T 2>/dev/null || true)
    case $state in
    idle) break ;;
    *inval* | *drain* | *down* | *fail*) fail "node localhost is $state" ;;
    esac
    sleep 0.2
done
[ "$state" = idle ] || fail "node localhost is not idle after 2 minutes (state: '${state:-no answer}')"
echo "export SLURM_CONF=$SLURM_CONF"
