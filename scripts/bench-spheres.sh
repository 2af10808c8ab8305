#!/usr/bin/env bash
# Sphere-scene benchmark against POV-Ray 3.7, interleaved in one run: the scenes of
# scripts/sphere_scenes.py (10k reflective spheres; 100k and 1M spheres as a flat layer and as a
# 3-D lattice), 1280x720, 1 sample per pixel, one point light, max trace level 8, on 1 and 2
# threads. quadray reads the spheres from a binary PLY file (`[[spheres]] path`), POV-Ray from
# `sphere` objects in its scene file. Reports medians (and min-max) over REPS rounds of:
# quadray load, BVH build and render CPU seconds, POV-Ray parse and trace CPU seconds, wall time
# and peak RSS of each whole process, and the POV-Ray / quadray ratios.
#   scripts/bench-spheres.sh [REPS=3]   (POV-Ray: apt-get install povray; its runs skipped if absent)
set -euo pipefail
cd "$(dirname "$0")/.."
reps=${1:-3}
cargo build --release -q -p quadray-cli
bin=$PWD/target/release/quadray
out=$(mktemp -d)
log=$out/log.txt
python3 scripts/sphere_scenes.py "$out" >&2
scenes="spheres10k-reflective spheres100k-flat spheres100k-lattice spheres1m-flat spheres1m-lattice"

timed() { # label, then the command; appends one line: label, GNU time's fields, the output
  local label=$1
  shift
  printf '%s ' "$label" >>"$log"
  /usr/bin/time -f 'TIME wall=%e rss_kb=%M' "$@" 2>&1 | tr '\n' ' ' >>"$log"
  echo >>"$log"
}
for rep in $(seq "$reps"); do
  echo "round $rep (load $(cut -d' ' -f1 /proc/loadavg))" >&2
  for s in $scenes; do
    for t in 1 2; do
      timed "quadray $s t=$t" "$bin" render "$out/$s.toml" -o "$out/q.png" -t "$t" --stats
      if command -v povray >/dev/null; then
        timed "povray $s t=$t" povray +I"$out/$s.pov" +O"$out/p.png" +W1280 +H720 -D -V +FN \
          File_Gamma=sRGB -A +WT"$t"
      fi
    done
  done
done
python3 - "$log" <<'PY'
import re, statistics, sys
rows = {}
def num(pattern, line):
    m = re.search(pattern, line)
    return float(m.group(1)) if m else float("nan")
for line in open(sys.argv[1]):
    key = " ".join(line.split()[:3])
    wall, rss = num(r"TIME wall=([\d.]+)", line), num(r"rss_kb=(\d+)", line) / 1024
    if line.startswith("quadray"):
        fields = (num(r"load ([\d.]+) s", line), num(r"BVH build ([\d.]+) s", line),
                  num(r"render CPU ([\d.]+) s", line), wall, rss)
    else:
        # The whole output is one line here: each field is read from its own section.
        parse = num(r"Parse Time:[^(]*\(([\d.]+) seconds\)", line)
        bounding = num(r"Bounding Time:[^(]*\(([\d.]+) seconds\)", line)
        trace = num(r"Trace Time:[^(]*\([\d.]+ seconds\)\s+using \d+ thread\(s\) with ([\d.]+)", line)
        fields = (parse + (bounding if bounding == bounding else 0.0), float("nan"), trace, wall, rss)
    rows.setdefault(key, []).append(fields)
def cell(v, i, digits=3):
    xs = [x[i] for x in v if x[i] == x[i]]
    if not xs:
        return "-"
    return f"{statistics.median(xs):.{digits}f} ({min(xs):.{digits}f}-{max(xs):.{digits}f})"
print("| run | load / parse+bounding s | BVH build s | render / trace CPU s | wall s | peak RSS MB | n |")
print("|---|---|---|---|---|---|---|")
for k, v in rows.items():
    print(f"| {k} | {cell(v, 0)} | {cell(v, 1)} | {cell(v, 2)} | {cell(v, 3)} | {cell(v, 4, 0)} | {len(v)} |")
print()
med = lambda key, i: statistics.median(x[i] for x in rows[key]) if key in rows else float("nan")
for k in rows:
    if k.startswith("quadray"):
        p = "povray" + k[len("quadray"):]
        if p in rows:
            print(f"- {k[8:]}: POV-Ray trace / quadray render CPU = {med(p, 2) / med(k, 2):.2f}; "
                  f"whole process wall = {med(p, 3) / med(k, 3):.2f}; peak RSS {med(k, 4):.0f} MB "
                  f"against {med(p, 4):.0f} MB")
PY
rm -rf "$out"
