#!/usr/bin/env bash
# Scene-graph benchmarks (docs/performance.md, "Instancing"), on scenes written by
# scripts/instancing_scenes.py into a temp dir:
#   - a glTF node DAG expanding to 2^18 box placements: load + 640x360 render wall time, peak RSS;
#   - the 871k-triangle dragon placed 1000 times: the same, and the memory report of --stats;
#   - 64 bunnies instanced vs baked, and scenes/columns.toml vs tests/scenes/columns-flat.toml:
#     render CPU medians over REPS interleaved runs at 1280x720 on 1 thread, and their ratio;
#   - 100 000 world-level instances of one mesh: bytes of top level per instance.
# The dragon is the npm one scripts/bench-speed.sh fetches (/tmp/quadray-speed); without it the
# shared assets' 202k-triangle dragon_res2 is used.
#   scripts/bench-instancing.sh [REPS=5]
set -euo pipefail
cd "$(dirname "$0")/.."
reps=${1:-5}
cargo build --release -q -p quadray-cli --features bench
bin=$PWD/target/release/quadray
out=$(mktemp -d)
dragon=/tmp/quadray-speed/meshes/dragon.obj
if [ ! -f "$dragon" ]; then
  dragon=$out/dragon_res2.obj
  zstd -q -d -f ../shared/assets/meshes/dragon_res2.obj.zst -o "$dragon"
fi
python3 scripts/instancing_scenes.py "$out" "$dragon" "$PWD/../shared/assets/meshes/bunny.obj"

run() { # scene -> "wall_s rss_MB" plus the --stats lines
  /usr/bin/time -f "%e %M" -o "$out/time" "$bin" render "$1" -o "$out/img.png" --res 640x360 -t 1 --stats \
    2>"$out/err" >/dev/null
  grep -E "^load|^structure" "$out/err"
  awk '{printf "wall %.2f s, peak RSS %.0f MB\n", $1, $2 / 1024}' "$out/time"
}
echo "== glTF DAG, 2^18 box placements"; run "$out/dag.gltf"
echo "== 1000 dragons ($(basename "$dragon"))"; run "$out/dragons.toml"
echo "== 100000 instances of one mesh"; run "$out/many-100000.toml"

median() { sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
cpu() { "$bin" render "$1" -o "$out/$2.png" -t 1 --res 1280x720 --stats 2>&1 | grep -o 'render CPU [0-9.]*' | awk '{print $3}'; }
for pair in "$out/bunnies-instanced.toml $out/bunnies-flat.toml" "scenes/columns.toml tests/scenes/columns-flat.toml"; do
  set -- $pair
  a=(); b=()
  for _ in $(seq "$reps"); do a+=("$(cpu "$1" a)"); b+=("$(cpu "$2" b)"); done
  ma=$(printf '%s\n' "${a[@]}" | median); mb=$(printf '%s\n' "${b[@]}" | median)
  echo "== $(basename "$1") vs $(basename "$2"): render CPU $ma s vs $mb s, ratio $(awk -v a="$ma" -v b="$mb" 'BEGIN {printf "%.2f", a / b}')"
  "$bin" compare "$out/a.png" "$out/b.png" | tail -1
done
rm -rf "$out"
