#!/usr/bin/env bash
# Fuzzing (docs/reliability.md): each cargo-fuzz target for RUNS executions (default 10^6), seeded
# from the files under 16 kB of scenes/ and ../shared/assets (copied into fuzz/corpus/, which git
# ignores; inputs are capped at 16 kB so that an execution takes milliseconds, not a whole mesh). Crashes land in
# fuzz/artifacts/TARGET/; copy each into tests/hostile/ so that `cargo test` replays it on stable.
#   scripts/fuzz.sh [RUNS=1000000] [TARGETS="toml_scene obj gltf render"]
# Needs the nightly toolchain and cargo-fuzz (`cargo +nightly install cargo-fuzz`).
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-1000000}
targets=${2:-toml_scene obj gltf render}
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
for t in $targets; do
  echo "== $t"
  cargo +nightly fuzz run --release "$t" "fuzz/corpus/$t" -- -runs="$runs" -max_len=16384 -max_total_time=3600 \
    -rss_limit_mb=4096 -timeout=10 -print_final_stats=1 2>&1 |
    grep -E "INITED|DONE|stat::|ERROR|SUMMARY|panicked|Test unit written" || true
done
