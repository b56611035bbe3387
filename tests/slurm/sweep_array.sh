#!/usr/bin/env bash
# Runs a small Fig. 6b sweep as a real Slurm job array on a single-node
# cluster started here (Debian's slurmctld, slurmd, munge), merges the shards,
# and checks that the merged points.csv equals the unsharded run byte for byte.
# Everything (config, state, spool, logs, sockets) lives in a temporary folder
# and is shut down at exit, each daemon by its own process id. It installs
# nothing: without Slurm and munge it exits with status 77 (skipped).
# Usage: tests/slurm/sweep_array.sh PATH/TO/fistage
set -euo pipefail

fistage=$(realpath "${1:?usage: sweep_array.sh PATH/TO/fistage}")
repo=$(cd "$(dirname "$0")/../.." && pwd)
shards=4

if [ -n "${FISTAGE_HIDE_OPTIONAL:-}" ] && [ "${FISTAGE_HIDE_OPTIONAL}" != 0 ]; then
    echo "Slurm hidden (FISTAGE_HIDE_OPTIONAL=$FISTAGE_HIDE_OPTIONAL)"
    exit 77
fi
for tool in slurmctld slurmd sbatch squeue scontrol sinfo munged; do
    if ! command -v "$tool" >/dev/null; then
        echo "$tool not found (Debian's slurmctld, slurmd, slurm-client and munge; .ci/run installs them)"
        exit 77
    fi
done

work=$(mktemp -d)
chmod 755 "$work"
export SLURM_CONF="$work/slurm.conf"
munge_socket="$work/munge/munge.socket"

alive() {
    local pid
    pid=$(cat "$1" 2>/dev/null) || return 1
    [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null
}

stop_cluster() {
    # slurmctld's helper (slurmscriptd) is its child: note its id first.
    local helpers=""
    if alive "$work/slurmctld.pid"; then
        helpers=$(pgrep -P "$(cat "$work/slurmctld.pid")" || true)
    fi
    scontrol shutdown >/dev/null 2>&1 || true
    for daemon in slurmctld slurmd munge/munged; do
        pidfile="$work/$daemon.pid"
        [ "$daemon" = munge/munged ] && kill "$(cat "$pidfile" 2>/dev/null)" 2>/dev/null
        for _ in $(seq 50); do
            alive "$pidfile" || break
            sleep 0.2
        done
        if alive "$pidfile"; then
            kill -TERM "$(cat "$pidfile")" 2>/dev/null || true
            sleep 1
            alive "$pidfile" && kill -KILL "$(cat "$pidfile")" 2>/dev/null
        fi
    done
    for pid in $helpers; do
        for _ in $(seq 25); do
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.2
        done
        kill -TERM "$pid" 2>/dev/null || true
    done
    rm -rf "$work"
}
trap stop_cluster EXIT

# munge with its own key, socket folder readable by all.
mkdir -p "$work/munge"
chmod 755 "$work/munge"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$work/munge/munge.key"
munged --force --key-file="$work/munge/munge.key" --socket="$munge_socket" \
    --pid-file="$work/munge/munged.pid" --log-file="$work/munge/munged.log" \
    --seed-file="$work/munge/munged.seed"

host=$(hostname -s)
mkdir -p "$work/state" "$work/spool"
cat >"$SLURM_CONF" <<CONF
ClusterName=fistage
SlurmctldHost=$host(127.0.0.1)
AuthType=auth/munge
AuthInfo=socket=$munge_socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
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
MinJobAge=3600
ReturnToService=2
MailProg=/bin/true
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=main Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF

slurmctld
slurmd
for _ in $(seq 100); do
    state=$(sinfo -h -o %T 2>/dev/null | head -n 1 || true)
    [ "$state" = "idle" ] && break
    sleep 0.2
done
if [ "$state" != "idle" ]; then
    echo "the node did not come up (state '$state')"
    tail -n 20 "$work/slurmctld.log" "$work/slurmd.log" || true
    echo "slurm: 0 passed, 1 failed"
    exit 1
fi

# A small grid of the paper's Fig. 6b sweep (12 points, 0.5 s each).
scenario="$work/fig06b_small.toml"
sed -e 's/points = 24/points = 4/' -e 's/^duration = 3.0 *#.*/duration = 0.5/' \
    -e "s|../../robots/|$repo/robots/|" "$repo/scenarios/paper/fig06b_fi_vp20.toml" >"$scenario"
sed -i '0,/points = 4/! s/points = 4/points = 3/' "$scenario"

"$fistage" sweep "$scenario" --out "$work/whole" --threads 1 >/dev/null
sbatch --wait --quiet --array=0-$((shards - 1)) --cpus-per-task=1 \
    --output="$work/task_%a.log" \
    --wrap "\"$fistage\" sweep \"$scenario\" --shard \${SLURM_ARRAY_TASK_ID}/$shards --out \"$work/shard\${SLURM_ARRAY_TASK_ID}\" --threads 1"
tasks=$(squeue -h -t all -o %i 2>/dev/null | wc -l)

merge_args=()
for i in $(seq 0 $((shards - 1))); do
    merge_args+=(--merge "$work/shard$i")
done
"$fistage" sweep "$scenario" --out "$work/merged" "${merge_args[@]}" >/dev/null

failed=0
if cmp -s "$work/whole/points.csv" "$work/merged/points.csv"; then
    echo "slurm job array of $shards shards ($tasks tasks seen by squeue): merged points.csv equals the unsharded run ($(($(wc -l <"$work/whole/points.csv") - 1)) points)"
else
    diff "$work/whole/points.csv" "$work/merged/points.csv" | head -n 20 || true
    failed=1
fi

# The same for a tolerance analysis: 64 stages of the Fig. 5b population.
population="$work/population.toml"
sed -e "s|../../robots/|$repo/robots/|" "$repo/scenarios/robust/fig05b_population.toml" >"$population"
"$fistage" robust "$population" --samples 64 --out "$work/robust_whole" --threads 1 >/dev/null
sbatch --wait --quiet --array=0-$((shards - 1)) --cpus-per-task=1 \
    --output="$work/robust_task_%a.log" \
    --wrap "\"$fistage\" robust \"$population\" --samples 64 --shard \${SLURM_ARRAY_TASK_ID}/$shards --out \"$work/robust\${SLURM_ARRAY_TASK_ID}\" --threads 1"
robust_merge=()
for i in $(seq 0 $((shards - 1))); do
    robust_merge+=(--merge "$work/robust$i")
done
"$fistage" robust "$population" --samples 64 --out "$work/robust_merged" "${robust_merge[@]}" >/dev/null
if cmp -s "$work/robust_whole/samples.csv" "$work/robust_merged/samples.csv"; then
    echo "slurm job array of $shards robust shards: merged samples.csv equals the unsharded run (64 samples)"
else
    diff "$work/robust_whole/samples.csv" "$work/robust_merged/samples.csv" | head -n 20 || true
    failed=1
fi

if [ "$failed" = 0 ]; then
    echo "slurm: 2 passed, 0 failed"
else
    echo "slurm: some failed"
    exit 1
fi
