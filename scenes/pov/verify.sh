#!/usr/bin/env bash
# Renders each given quadray scene (default: every scenes/*.toml) with POV-Ray 3.7 through
# toml2pov.py and with quadray, both at the scene's resolution with one ray through each pixel
# centre (POV-Ray without anti-aliasing), and prints `quadray compare`'s measures.
#   apt-get install -y povray     # Debian 12: POV-Ray 3.7.0.10
#   scenes/pov/verify.sh [SCENE.toml ...]     (from the repository root; OUT=dir keeps images)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${OUT:-$(mktemp -d)}
mkdir -p "$out"
cargo build --release -q -p quadray-cli
quadray=target/release/quadray
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(scenes/*.toml)
for scene in "${scenes[@]}"; do
  name=$(basename "$scene" .toml)
  read -r w h < <(python3 -c "
import tomllib, sys
r = tomllib.load(open(sys.argv[1], 'rb')).get('render', {}).get('resolution', [640, 480])
w, h = r
k = min(1.0, 320 / w, 240 / h)   # the regression suite's size
print(round(w * k), round(h * k))" "$scene")
  python3 scenes/pov/toml2pov.py "$scene" "$out/$name.pov" "$w" "$h"
  (cd "$out" && povray "+I$name.pov" "+O$name.pov.png" "+W$w" "+H$h" -D -V +FN \
      File_Gamma=sRGB -A +WT2 2>"$name.pov.log") || { echo "$name: POV-Ray failed, see $out/$name.pov.log"; continue; }
  "$quadray" render "$scene" -o "$out/$name.quadray.png" --res "${w}x$h" --spp 1 -q
  echo "$name: $("$quadray" compare "$out/$name.pov.png" "$out/$name.quadray.png" \
      --diff "$out/$name.diff.png" 2>&1 | tr '\n' ' ')"
done
