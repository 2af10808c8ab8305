#!/usr/bin/env bash
# The Slurm recipe's end-to-end check: renders a frame as a Slurm job array with
# scripts/farm/slurm-render.sh, renders the same frame in one process, and compares the two files
# byte for byte with cmp. Exits 0 only when they are identical (and slurm-render.sh found every
# piece rendered by a Slurm task). Needs a Slurm that answers (scripts/farm/slurm-up.sh).
#
#   scripts/farm/check.sh [SCENE] [N] [RENDER_ARGS] [WORKDIR]
#
# Defaults: scenes/defense.toml, 4 pieces, "--res 160x90 --spp 2", a temporary directory (removed
# when the check passes, kept for a look when it fails). Environment: as slurm-render.sh (QUADRAY,
# CPUS, TIMEOUT, RETRIES, DROP_PIECE); TIMEOUT also bounds the one-process render.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
scene=${1:-$here/../../scenes/defense.toml}
n=${2:-4}
render_args=${3-"--res 160x90 --spp 2"}
work=${4:-}
if [ -z "$work" ]; then
    work=$(mktemp -d)
    # shellcheck disable=SC2317 # called by the trap
    cleanup() {
        if [ "$1" = 0 ]; then rm -rf "$work"; else echo "check: kept $work" >&2; fi
    }
    trap 'cleanup $?' EXIT
fi
quadray=${QUADRAY:-quadray}

"$here/slurm-render.sh" "$scene" "$n" "$render_args" "$work" "$work/frame.exr"
# shellcheck disable=SC2086 # $render_args is several options
timeout "${TIMEOUT:-600}" "$quadray" render "$scene" $render_args -q -o "$work/single.exr"
cmp "$work/single.exr" "$work/frame.exr"
echo "check: the merged frame is the one-process render byte for byte ($(stat -c %s "$work/frame.exr") bytes)"
