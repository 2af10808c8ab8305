#!/usr/bin/env bash
# Renders one frame as a Slurm job array (docs/distributed.md, "Slurm job array"): submits
# scripts/farm/render.sbatch for pieces 0 .. N-1 and waits, submits again as one array the pieces
# `quadray merge --missing` still lists, then merges the pieces into OUTPUT. It then checks that
# every piece was rendered by a Slurm task of this run, from the tasks' output files.
#
#   scripts/farm/slurm-render.sh SCENE N RENDER_ARGS WORKDIR OUTPUT
#   e.g. scripts/farm/slurm-render.sh scenes/defense.toml 64 "--res 3840x2160 --spp 256" work frame.exr
#
# Pieces go to WORKDIR/parts, each task's output to WORKDIR/slurm-JOB_TASK.out; earlier ones there
# are removed first. Environment:
#   QUADRAY     the binary (default: quadray on PATH); every task runs it
#   CPUS        CPUs (threads) per task (default 4, or a node's CPU count where that is smaller)
#   TIMEOUT     seconds one array may take from submission to its end (default 600)
#   RETRIES     rounds of submitting the missing pieces again (default 2)
#   DROP_PIECE  a piece index to delete after the first round, so the retry has work to do
# On a timeout or a frame still incomplete, prints the queue, the jobs, the tasks' output and the
# daemons' logs, cancels this run's jobs, and exits 1.
set -euo pipefail

if [ $# -ne 5 ]; then
    sed -n '2,/^set /s/^# \{0,1\}//p' "$0" >&2
    exit 2
fi
scene=$1 n=$2 render_args=$3 work=$4 out=$5
[[ $n =~ ^[1-9][0-9]*$ ]] || { echo "slurm-render: N must be a positive number, not '$n'" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
# Absolute, since the tasks run it wherever Slurm starts them.
quadray=$(realpath -e "$(command -v "${QUADRAY:-quadray}")" 2>/dev/null) \
    || { echo "slurm-render: no binary ${QUADRAY:-quadray} (set QUADRAY)" >&2; exit 1; }
timeout_s=${TIMEOUT:-600}
retries=${RETRIES:-2}
node_cpus=$(timeout 30 sinfo -h -N -o %c | sort -n | tail -n 1) || node_cpus=
if [ -z "$node_cpus" ]; then
    echo "slurm-render: Slurm does not answer (scripts/farm/slurm-up.sh starts one)" >&2
    exit 1
fi
cpus=${CPUS:-$((node_cpus < 4 ? node_cpus : 4))}
if [ "$cpus" -gt "$node_cpus" ]; then  # Slurm would queue such tasks forever (PartitionConfig)
    echo "slurm-render: CPUS=$cpus but the largest node has $node_cpus" >&2
    exit 1
fi
mkdir -p "$work/parts"
work=$(cd "$work" && pwd)
parts=$work/parts
rm -f "$parts"/part-*.exr "$work"/slurm-*.out
job_ids=()  # this run's job IDs

# render.sbatch reads these; sbatch passes the submitter's environment on to the tasks.
export SCENE=$scene N=$n RENDER_ARGS=$render_args PARTS=$parts QUADRAY=$quadray

# The queue, this run's jobs, the tasks' output and the daemons' logs, then exit 1.
fail() {
    local j f
    echo "slurm-render: $*" >&2
    echo "--- squeue" >&2
    timeout 30 squeue -o '%.12i %.9P %.10j %.8T %.10M %R' >&2 || true
    for j in "${job_ids[@]}"; do
        echo "--- scontrol show job $j" >&2
        timeout 30 scontrol show job "$j" >&2 || true
        timeout 30 scancel "$j" || true
    done
    for f in "$work"/slurm-*.out /var/log/slurm/slurmctld.log /var/log/slurm/slurmd.log; do
        [ -s "$f" ] && { echo "--- last lines of $f" >&2; tail -n 15 "$f" >&2; }
    done
    exit 1
}

# Waits until job $1 has left the queue (all its tasks ended), at most timeout_s seconds.
wait_job() {
    local deadline=$((SECONDS + timeout_s)) left
    while :; do
        if left=$(timeout 30 squeue -h -j "$1" -o %i 2>&1); then
            [ -n "$left" ] || return 0
        elif [[ $left == *"Invalid job id"* ]]; then
            return 0  # ended long enough ago for the controller to forget it
        fi            # else the controller did not answer this time: ask again
        [ "$SECONDS" -lt "$deadline" ] || fail "job $1 still queued after ${timeout_s} s"
        sleep 1
    done
}

# Submits render.sbatch as an array over the indices $1 ("0-63", "5,17") and waits for it.
submit() {
    local id
    id=$(timeout 30 sbatch --parsable --array="$1" --cpus-per-task="$cpus" \
        --output="$work/slurm-%A_%a.out" "$here/render.sbatch") || fail "sbatch failed"
    id=${id%%;*}  # --parsable prints JOBID[;CLUSTER]
    job_ids+=("$id")
    echo "slurm-render: job $id: pieces $1 of $n, $cpus CPUs each"
    wait_job "$id"
}

start=$SECONDS
submit "0-$((n - 1))"
if [ -n "${DROP_PIECE:-}" ]; then
    rm "$parts/part-$DROP_PIECE.exr" || fail "no piece $DROP_PIECE to drop"
    echo "slurm-render: dropped piece $DROP_PIECE"
fi
# Pieces whose task died (or that were dropped) are rendered again, as one array.
for _ in $(seq "$retries"); do
    compgen -G "$parts/part-*.exr" >/dev/null || fail "no task wrote a piece"
    missing=$("$quadray" merge "$parts"/part-*.exr --missing | paste -sd, -) \
        || fail "merge --missing failed"
    [ -n "$missing" ] || break
    submit "$missing"
done
"$quadray" merge "$parts"/part-*.exr -o "$out" -q || fail "merge failed"

# Every piece comes from a task of this run: its output names the piece and the job, and the
# dropped piece was rendered again by a later job.
for i in $(seq 0 $((n - 1))); do
    by=
    for j in "${job_ids[@]}"; do
        if grep -qF "quadray piece $i/$n: job ${j}_$i " "$work/slurm-${j}_$i.out" 2>/dev/null; then
            by=$j
        fi
    done
    [ -n "$by" ] || fail "piece $i has no Slurm task's output from this run"
    if [ "$i" = "${DROP_PIECE:-}" ] && [ "$by" = "${job_ids[0]}" ]; then
        fail "dropped piece $i was not rendered again"
    fi
done
echo "slurm-render: $n pieces by Slurm jobs ${job_ids[*]}, merged into $out in $((SECONDS - start)) s"
