#!/usr/bin/env bash
# How closely `--time-limit` keeps its time: each scene rendered with time limits of 0.5, 1 and
# 2 s (480x270, one thread), RUNS times in alternation with OTHER_QUADRAY when given one; prints
# a markdown table of the render time the final line reports (the median, its spread and how
# far over the limit) and the estimated image error reached. The first round of 8 samples always
# completes, so a limit below its time is overrun by design.
#   scripts/bench-time-limit.sh [RUNS=3] [OTHER_QUADRAY] [LIMITS="0.5 1 2"] [SCENES="grid defense reflective mesh"]
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
other=${2:-}
limits=${3:-"0.5 1 2"}
scenes=${4:-"grid defense reflective mesh"}
[ -z "$other" ] || [ -x "$other" ] || { echo "error: $other is not an executable" >&2; exit 1; }
cargo build --release -q -p quadray-cli
this=target/release/quadray
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
zstd -q -d -f ../shared/assets/meshes/obvhs_kitchen/kitchen.obj.zst -o "$tmp/kitchen.obj"
python3 scripts/harness_scenes.py ../shared/peers/povray/scenes.json "$tmp"

bins=(this)
[ -z "$other" ] || bins+=(other)
# One render's reported render time and estimated error, as "seconds error".
measure() { # binary, scene, limit
  "$1" render "$2" --res 480x270 -t 1 --time-limit "$3" -o "$tmp/out.png" 2>&1 \
    | grep 'adaptive,' \
    | sed -E 's/.*estimated image error ([0-9.e+-]+) RMSE.* in ([0-9.]+) s .*/\2 \1/'
}
echo "| scene | limit (s) | build | render time, median (s) | over the limit | runs (s) | estimated error |"
echo "|---|---:|---|---:|---:|---|---:|"
for name in $scenes; do
  case $name in
    defense | reflective) scene=scenes/$name.toml ;;
    grid | mesh) scene=$tmp/$name.toml ;;
    *) echo "unknown scene $name" >&2; exit 2 ;;
  esac
  for limit in $limits; do
    for b in "${bins[@]}"; do : >"$tmp/$b.txt"; done
    for _ in $(seq "$runs"); do
      for b in "${bins[@]}"; do
        measure "${!b}" "$scene" "$limit" >>"$tmp/$b.txt"
      done
    done
    for b in "${bins[@]}"; do
      sort -n "$tmp/$b.txt" | awk -v n="$name" -v t="$limit" -v b="$b" '
        { s[NR] = $1; e[NR] = $2 }
        END {
          m = int((NR + 1) / 2)
          printf "| %s | %s | %s | %.3f | %+.0f%% | %.3f–%.3f | %s |\n", n, t, b, s[m], (s[m] / t - 1) * 100, s[1], s[NR], e[m]
        }'
    done
  done
done
