#!/usr/bin/env bash
# Renders each given quadray scene (default: every scenes/*.toml and scenes/*.gltf) with POV-Ray
# 3.7 and with quadray, both at the regression suite's size with one ray through each pixel
# centre (POV-Ray without anti-aliasing), and prints `quadray compare`'s measures.
# TOML scenes go through toml2pov.py; glTF files written by `quadray convert`, and TOML scenes that
# read OBJ or glTF files ([[mesh]] path, [[include]]), through `quadray convert` and gltf2pov.py.
#   apt-get install -y povray     # Debian 12: POV-Ray 3.7.0.10
#   scenes/pov/verify.sh [SCENE.toml|SCENE.gltf ...]   (from the repository root; OUT=dir keeps images)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${OUT:-$(mktemp -d)}
mkdir -p "$out"
cargo build --release -q -p quadray-cli
quadray=target/release/quadray
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(scenes/*.toml scenes/*.gltf)
for scene in "${scenes[@]}"; do
  name=$(basename "${scene%.*}")
  read -r w h kind < <(python3 -c "
import json, tomllib, sys
p = sys.argv[1]
if p.endswith('.gltf'):
    g = json.load(open(p))
    r = g['scenes'][g.get('scene', 0)].get('extras', {}).get('quadray', {}).get('resolution', [640, 480])
    kind = 'gltf'
else:
    s = tomllib.load(open(p, 'rb'))
    r = s.get('render', {}).get('resolution', [640, 480])
    reads = s.get('include') or any('path' in m for m in s.get('mesh', []))
    kind = 'convert' if reads else 'toml'
w, h = r
k = min(1.0, 320 / w, 240 / h)   # the regression suite's size
print(round(w * k), round(h * k), kind)" "$scene")
  case $kind in
    toml) python3 scenes/pov/toml2pov.py "$scene" "$out/$name.pov" "$w" "$h" ;;
    gltf) python3 scenes/pov/gltf2pov.py "$scene" "$out/$name.pov" "$w" "$h" ;;
    convert)
      "$quadray" convert -q "$scene" -o "$out/$name.gltf"
      python3 scenes/pov/gltf2pov.py "$out/$name.gltf" "$out/$name.pov" "$w" "$h" ;;
  esac
  (cd "$out" && povray "+I$name.pov" "+O$name.pov.png" "+W$w" "+H$h" -D -V +FN \
      File_Gamma=sRGB -A +WT2 2>"$name.pov.log") || { echo "$name: POV-Ray failed, see $out/$name.pov.log"; continue; }
  # Point-sampled textures, as POV-Ray samples them (the references filter them; see README).
  "$quadray" render "$scene" -o "$out/$name.quadray.png" --res "${w}x$h" --spp 1 --texture-filter none -q
  echo "$name: $("$quadray" compare "$out/$name.pov.png" "$out/$name.quadray.png" \
      --diff "$out/$name.diff.png" 2>&1 | tr '\n' ' ')"
done
