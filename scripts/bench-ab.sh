#!/usr/bin/env bash
# Two quadray builds timed against each other on one scene: render CPU (from `--stats`), one
# thread, ROUNDS rounds alternating which build runs first, so the shared host's load falls on
# both alike. Prints each build's minimum and median and the median of the rounds' ratios B / A,
# the figure docs/performance.md reports for a change.
#
#   scripts/bench-ab.sh A B ROUNDS SCENE [RENDER OPTIONS...]
#
# A and B are quadray binaries (say a build of the commit before a change, copied aside, and
# target/release/quadray); SCENE and the options go to `quadray render`, e.g.
# `scripts/bench-ab.sh /tmp/old target/release/quadray 21 scenes/reflective.toml --res 640x360`.
set -euo pipefail
[ $# -ge 4 ] || { sed -n 2,11p "$0" >&2; exit 2; }
a=$1 b=$2 rounds=$3
shift 3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cpu() { # binary, scene and options: the render's CPU seconds
  local bin=$1
  shift
  "$bin" render "$@" -t 1 --stats -o "$tmp/image.png" 2>&1 | grep -o 'render CPU [0-9.]*' | cut -d' ' -f3 \
    || { echo "error: $bin render $* printed no render CPU" >&2; exit 1; }
}
for i in $(seq "$rounds"); do
  if [ $((i % 2)) = 0 ]; then
    ta=$(cpu "$a" "$@"); tb=$(cpu "$b" "$@")
  else
    tb=$(cpu "$b" "$@"); ta=$(cpu "$a" "$@")
  fi
  echo "$ta $tb" >> "$tmp/times"
done
python3 - "$tmp/times" <<'PY'
import statistics as st, sys
rounds = [tuple(map(float, line.split())) for line in open(sys.argv[1])]
a, b = [r[0] for r in rounds], [r[1] for r in rounds]
print(f"A min {min(a):.4f} s, median {st.median(a):.4f} s; B min {min(b):.4f} s, median {st.median(b):.4f} s; "
      f"median of B/A {st.median(y / x for x, y in rounds):.3f} over {len(rounds)} rounds")
PY
