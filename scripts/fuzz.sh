#!/usr/bin/env bash
# Fuzzing (docs/reliability.md): each cargo-fuzz target for RUNS executions (default 10^6), seeded
# from the files under 16 kB of scenes/ and ../shared/assets (copied into fuzz/corpus/, which git
# ignores; inputs are capped at 16 kB so that an execution takes milliseconds, not a whole mesh). Crashes land in
# fuzz/artifacts/TARGET/; copy each into tests/hostile/ so that `cargo test` replays it on stable.
#   scripts/fuzz.sh [RUNS=1000000] [TARGETS="toml_scene obj gltf render cli"]
# Needs cargo-fuzz (`cargo install cargo-fuzz`) and its sanitizer flags: the nightly toolchain
# where there is one, else the stable one with RUSTC_BOOTSTRAP=1 (as on the project's machines).
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-1000000}
targets=${2:-toml_scene obj gltf render cli}
shared=../shared/assets
seed() { # target, files...
  local dir=fuzz/corpus/$1; shift
  mkdir -p "$dir"
  for f in "$@"; do [ -f "$f" ] && [ "$(stat -c %s "$f")" -lt 16384 ] && cp -f --no-preserve=mode "$f" "$dir/" 2>/dev/null || true; done
}
seed toml_scene scenes/*.toml tests/scenes/*.toml tests/hostile/toml/*
seed render scenes/*.toml tests/scenes/*.toml tests/hostile/toml/*
seed obj $shared/meshes/*.obj $shared/meshes/*/*.obj tests/hostile/obj/*
seed gltf scenes/*.gltf $shared/gltf/khronos/*/glTF-Embedded/*.gltf $shared/gltf/khronos/*/glTF-Binary/*.glb tests/hostile/gltf/*
# Command lines (arguments separated by NUL) for the cli target.
mkdir -p fuzz/corpus/cli
i=0
for line in 'render|s.toml|--time-limit|1e308' 'render|s.toml|--target-error|0.01|--min-spp|2' \
  'render|s.toml|--res|640x480|--spp|4' 'check|s.toml|--set|render.spp=64' \
  'render|s.toml|--set|sphere[0].radius=2|--set|camera.orbit.yaw=30' 'render|s.toml|--crop|0,0.5,0,1' \
  'render|s.toml|--tile|3/16|-o|a.exr' 'quadric|cone|-a|2|--clip|1e3'; do
  printf '%s' "$line" | tr '|' '\0' > "fuzz/corpus/cli/seed-$i"; i=$((i + 1))
done
if rustup toolchain list 2>/dev/null | grep -q nightly; then fuzz="cargo +nightly fuzz"
else fuzz="env RUSTC_BOOTSTRAP=1 cargo fuzz"; fi
for t in $targets; do
  echo "== $t"
  $fuzz run --release "$t" "fuzz/corpus/$t" -- -runs="$runs" -max_len=16384 -max_total_time=3600 \
    -rss_limit_mb=4096 -timeout=10 -print_final_stats=1 2>&1 |
    grep -E "INITED|DONE|stat::|ERROR|SUMMARY|panicked|Test unit written" || true
done
