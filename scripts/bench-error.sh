#!/usr/bin/env bash
# Speed against image error, quadray (uniform spp at every power of two to 64, image-error
# targets, per-pixel targets, time limits and previews) against POV-Ray 3.7 (its adaptive
# anti-aliasing at several thresholds and depths), each against its own reference whose own
# error is measured, on four scenes:
#   - defense and reflective: scenes/*.toml, translated to POV-Ray by scenes/pov/toml2pov.py;
#   - grid and mesh (the kitchen): the POV-Ray harness's own .pov files and quadray ports of its
#     renderer-neutral scenes.json (scripts/harness_scenes.py).
# One thread each (CPU seconds), 480x270, max trace level as each scene says. Writes
# docs/image-error/<scene>.{md,svg} and <scene>-reference.png.
#   scripts/bench-error.sh [RUNS=3] [SCENES="defense reflective grid mesh"]
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
scenes=${2:-"defense reflective grid mesh"}
cargo build --release -q -p quadray-cli --features bench
bin=target/release/quadray
harness=../shared/peers/povray
out=docs/image-error
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
zstd -q -d -f ../shared/assets/meshes/obvhs_kitchen/kitchen.obj.zst -o "$tmp/kitchen.obj"
python3 scripts/harness_scenes.py "$harness/scenes.json" "$tmp"
for name in $scenes; do
  case $name in
    defense | reflective)
      scene=scenes/$name.toml
      python3 scenes/pov/toml2pov.py "$scene" "$tmp/$name.pov"
      pov=$tmp/$name.pov ;;
    grid | mesh)
      scene=$tmp/$name.toml
      pov=$harness/pov/$name.pov ;;
    *) echo "unknown scene $name" >&2; exit 2 ;;
  esac
  echo "== $name (load $(cut -d' ' -f1 /proc/loadavg))" >&2
  "$bin" bench images --scene "$scene" --povray "$pov" --res 480x270 --runs "$runs" -t 1 \
    --out "$out" --name "$name" --quiet
done
