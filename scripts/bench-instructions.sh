#!/usr/bin/env bash
# Instruction counts of the standard frames and of `bench rays`, for judging a change on a noisy
# machine: callgrind counts the instructions a binary executes, the same on every run, where the
# CPU time of the same render spreads by 10-20% while other tenants share the cores. Fewer
# instructions are not always less time (branches, cache misses and code layout count too), so a
# change that trades instructions for branches or memory traffic still wants interleaved timed
# rounds; docs/performance.md says which changes were judged how.
#
#   scripts/bench-instructions.sh [OTHER_QUADRAY]
#
# Counts the render alone (`quadray::render::render_with_aovs`, one thread) of scenes/reflective.toml,
# scenes/defense.toml, the harness's quadric grid and lit kitchen (320x180), the kitchen's
# camera-rays-only frame (640x360, no lights, 1 spp), and the closest-hit queries of `bench rays`
# on the kitchen's coherent rays (`Accel::closest`'s AVX2 copy); the last two need the files
# scripts/bench-speed.sh writes under /tmp/quadray-speed. With OTHER_QUADRAY (a quadray
# binary built with `--features bench`, say from another commit), counts both side by side and
# checks that their images are byte-identical. Needs valgrind (apt-get install valgrind) and, for
# the harness scenes and rays, ../shared.
set -euo pipefail
cd "$(dirname "$0")/.."
other=${1:-}
command -v valgrind >/dev/null || { echo "error: valgrind is needed (apt-get install valgrind)" >&2; exit 1; }
[ -z "$other" ] || [ -x "$other" ] || { echo "error: $other is not an executable" >&2; exit 1; }
cargo build --release -q -p quadray-cli --features bench
this=target/release/quadray
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
zstd -q -d -f ../shared/assets/meshes/obvhs_kitchen/kitchen.obj.zst -o "$tmp/kitchen.obj"
python3 scripts/harness_scenes.py ../shared/peers/povray/scenes.json "$tmp"
# The camera-rays-only kitchen frame and the kitchen's coherent rays (the harness's RAYS format)
# of scripts/bench-speed.sh, which writes them.
frame=/tmp/quadray-speed/kitchen.frame.toml
rays=/tmp/quadray-speed/rays/kitchen.coherent.rays

count() { # binary, toggle, args...: the instructions callgrind counts inside the toggled function
  local bin=$1 toggle=$2
  shift 2
  valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.out" --toggle-collect="$toggle" \
    "$bin" "$@" 2>&1 >/dev/null | grep -oE 'refs: +[0-9,]+' | tr -d ', ' | cut -d: -f2
}
render() { # binary, scene, resolution, output
  count "$1" 'quadray::render::render_with_aovs' render "$2" --res "$3" -t 1 -o "$4"
}

printf '| work | instructions (M)%s |\n|---|---:%s|\n' "${other:+ | other binary (M) | change}" "${other:+|---:|---:}"
row() { # label, this count, other count
  if [ -n "$other" ]; then
    awk -v l="$1" -v a="$2" -v b="$3" 'BEGIN { printf "| %s | %.1f | %.1f | %+.1f%% |\n", l, a / 1e6, b / 1e6, (a - b) / b * 100 }'
  else
    awk -v l="$1" -v a="$2" 'BEGIN { printf "| %s | %.1f |\n", l, a / 1e6 }'
  fi
}
while read -r label scene res; do
  a=$(render "$this" "$scene" "$res" "$tmp/a.exr")
  b=""
  if [ -n "$other" ]; then
    b=$(render "$other" "$scene" "$res" "$tmp/b.exr")
    cmp -s "$tmp/a.exr" "$tmp/b.exr" || echo "note: $label renders differ between the two binaries" >&2
  fi
  row "$label, $res" "$a" "$b"
done <<EOF
reflective scenes/reflective.toml 320x180
defense scenes/defense.toml 320x180
grid $tmp/grid.toml 320x180
lit-kitchen $tmp/mesh.toml 320x180
EOF
if [ -f "$frame" ]; then
  a=$(render "$this" "$frame" 640x360 "$tmp/a.exr")
  b=""
  [ -z "$other" ] || b=$(render "$other" "$frame" 640x360 "$tmp/b.exr")
  row "kitchen camera-rays-only, 640x360" "$a" "$b"
else
  echo "note: $frame not found (scripts/bench-speed.sh writes it): the frame skipped" >&2
fi
if [ -f "$rays" ]; then
  toggle='quadray::accel::Accel::closest_avx2'
  a=$(count "$this" "$toggle" bench rays "$tmp/kitchen.obj" "$rays" --runs 1 -t 1)
  b=""
  [ -z "$other" ] || b=$(count "$other" "$toggle" bench rays "$tmp/kitchen.obj" "$rays" --runs 1 -t 1)
  row "bench rays, kitchen coherent, closest hits (AVX2 path)" "$a" "$b"
else
  echo "note: $rays not found (scripts/bench-speed.sh writes it): bench rays skipped" >&2
fi
