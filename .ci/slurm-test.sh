#!/usr/bin/env bash
# A real single-node Slurm cluster for the sweep's array-job sharding: installs Debian's Slurm
# and MUNGE if missing (root: CI runs as root), configures both in a temporary folder (their own
# key, socket, ports, state and logs; nothing in /etc is used), starts munged, slurmctld and
# slurmd, submits a sweep as `sbatch --array` (each task finds its shard in SLURM_ARRAY_TASK_*),
# waits, merges, and checks the merged map equals the unsharded run byte for byte. Stops the
# daemons and removes the folder whatever happens.
#
#   bash .ci/slurm-test.sh [path/to/twv]        (default target/debug/twv)
#   bash .ci/slurm-test.sh --install-only       (the packages only; the test command runs this
#                                                in the background while Rust builds)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
if [ "$(id -u)" -ne 0 ]; then
    echo "slurm test: needs root (to install and run the Slurm daemons); not run"
    exit 1
fi
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        slurmctld slurmd slurm-client munge >/dev/null
fi
[ "${1:-}" = "--install-only" ] && exit 0
twv="$(realpath "${1:-target/debug/twv}")"
[ -x "$twv" ] || { echo "slurm test: no twv binary at $twv (build it first)"; exit 1; }

work="$(mktemp -d /tmp/twv-slurm.XXXXXX)"
munge_pid=""
cleanup() {
    status=$?
    SLURM_CONF="$work/slurm.conf" scontrol shutdown >/dev/null 2>&1 || true
    pids=()
    for p in "$work"/slurmctld.pid "$work"/slurmd.pid; do
        [ -f "$p" ] && pids+=("$(cat "$p")")
    done
    [ -n "$munge_pid" ] && pids+=("$munge_pid")
    for pid in "${pids[@]}"; do
        kill "$pid" 2>/dev/null || true
    done
    # Wait (at most 10 s) for the daemons to exit before their folder goes.
    for pid in "${pids[@]}"; do
        for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    done
    if [ $status -ne 0 ]; then
        echo "--- slurmctld.log"; tail -20 "$work/slurmctld.log" 2>/dev/null || true
        echo "--- slurmd.log"; tail -20 "$work/slurmd.log" 2>/dev/null || true
        echo "--- munged.log"; tail -5 "$work/munged.log" 2>/dev/null || true
        for f in "$work"/job-*.out; do [ -f "$f" ] && { echo "--- $f"; cat "$f"; }; done
    fi
    rm -rf "$work"
    exit $status
}
trap cleanup EXIT

# MUNGE with its own key and socket.
mkdir -p "$work/munge" "$work/state" "$work/spool"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 700 "$work/munge"; chmod 400 "$work/munge/munge.key"
munged --force --key-file="$work/munge/munge.key" --socket="$work/munge/munge.sock" \
    --pid-file="$work/munge/munged.pid" --log-file="$work/munged.log" \
    --seed-file="$work/munge/munged.seed"
munge_pid="$(cat "$work/munge/munged.pid")"

# Two free ports on the loopback for slurmctld and slurmd.
read -r ctld_port slurmd_port < <(python3 - <<'PY'
import socket
ports = []
socks = []
for _ in range(2):
    s = socket.socket(); s.bind(("127.0.0.1", 0)); ports.append(s.getsockname()[1]); socks.append(s)
print(*ports)
PY
)
host="$(hostname -s)"
cat > "$work/slurm.conf" <<CONF
ClusterName=twv-test
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.sock
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
SwitchType=switch/none
ReturnToService=2
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$work/slurm.conf"
slurmctld
slurmd
for _ in $(seq 60); do
    state="$(sinfo -h -N -o %t 2>/dev/null || true)"
    [ "$state" = "idle" ] && break
    sleep 0.5
done
[ "$state" = "idle" ] || { echo "slurm test: the node did not come up (state '$state')"; exit 1; }
echo "slurm: $(sinfo --version), node $host idle"

# The sweep: 4 array tasks, each one shard (from SLURM_ARRAY_TASK_ID/_MIN/_COUNT).
sweep=(sweep --kp 0:8000:12 --kd 0:4000:7 --metric max-lyapunov --quiet)
cat > "$work/job.sh" <<JOB
#!/bin/bash
exec "$twv" ${sweep[*]} --out "$work/array"
JOB
chmod +x "$work/job.sh"
sbatch --wait --array=0-3 --cpus-per-task=1 --output="$work/job-%a.out" "$work/job.sh"
ls "$work/array"/shard-*-of-4.json | wc -l | grep -qx 4 \
    || { echo "slurm test: expected 4 shard files"; ls "$work/array"; exit 1; }
"$twv" --quiet merge "$work/array"

"$twv" "${sweep[@]}" --shard 0/1 --out "$work/whole"
"$twv" --quiet merge "$work/whole"
for f in map.csv map.json map.svg; do
    cmp "$work/array/$f" "$work/whole/$f"
done
echo "slurm test: 1 passed, 0 failed (sbatch --array of 4 shards merged to the unsharded map's bytes)"
