#!/usr/bin/env bash
# The measured run of docs/distributed.md: one frame rendered whole, then in N pieces run P at a
# time (one thread each, as farm tasks on single cores), merged, and compared byte for byte.
# Prints the CPU seconds of the whole render and of every piece, their sum, and the slowest piece.
#
#   scripts/distributed-run.sh [SCENE] [WxH] [SPP] [PIECES] [PARALLEL]
set -euo pipefail
scene=${1:-scenes/defense.toml}
res=${2:-1920x1080}
spp=${3:-64}
pieces=${4:-16}
parallel=${5:-2}
quadray=${QUADRAY:-target/release/quadray}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

cpu() { awk '{print $1 + $2}' "$1"; }  # user + system seconds, as /usr/bin/time -f "%U %S" wrote them

/usr/bin/time -f "%U %S %e" -o "$out/whole.time" \
    "$quadray" render "$scene" --res "$res" --spp "$spp" -o "$out/whole.exr" -q
echo "whole render: $(cpu "$out/whole.time") CPU s, $(awk '{print $3}' "$out/whole.time") s wall"

start=$(date +%s.%N)
seq 0 $((pieces - 1)) | xargs -P "$parallel" -I{} /usr/bin/time -f "%U %S %e" -o "$out/{}.time" \
    "$quadray" render "$scene" --res "$res" --spp "$spp" -t 1 -q --tile "{}/$pieces" -o "$out/part-{}.exr"
wall=$(echo "$(date +%s.%N) - $start" | bc)
total=0
slowest=0
for i in $(seq 0 $((pieces - 1))); do
    c=$(cpu "$out/$i.time")
    echo "piece $i/$pieces: $c CPU s"
    total=$(echo "$total + $c" | bc)
    slowest=$(echo "if ($c > $slowest) $c else $slowest" | bc)
done
echo "pieces: $total CPU s in all, slowest $slowest s, $wall s wall at $parallel at a time"
"$quadray" merge "$out"/part-*.exr -o "$out/merged.exr" -q
cmp "$out/whole.exr" "$out/merged.exr" && echo "merged frame: byte-identical to the whole render"
