#!/usr/bin/env bash
# Render benchmark: scenes/defense.toml at 1280x720, 1 and 4 spp, 1 and 2 threads, and the POV-Ray
# `reflective` scene side by side with its quadray port (scenes/reflective.toml), interleaved in one
# run. Reports medians over REPS runs of wall time, CPU-seconds and Mrays/s.
#   scripts/bench-render.sh [REPS]      (POV-Ray: apt-get install povray; skipped if absent)
set -euo pipefail
cd "$(dirname "$0")/.."
reps=${1:-5}
cargo build --release -q -p quadray-cli
bin=target/release/quadray
pov_dir=../shared/peers/povray/pov
out=$(mktemp -d)
log=$out/log.txt
for rep in $(seq "$reps"); do
  for spp in 1 4; do
    for t in 1 2; do
      printf 'quadray defense spp=%s t=%s ' "$spp" "$t" >>"$log"
      "$bin" render scenes/defense.toml -o "$out/d.png" --res 1280x720 --spp "$spp" -t "$t" --stats 2>&1 | tr '\n' ' ' >>"$log"
      echo >>"$log"
    done
  done
  for t in 1 2; do
    printf 'quadray reflective spp=1 t=%s ' "$t" >>"$log"
    "$bin" render scenes/reflective.toml -o "$out/r.png" -t "$t" --stats 2>&1 | tr '\n' ' ' >>"$log"
    echo >>"$log"
    if command -v povray >/dev/null && [ -f "$pov_dir/reflective.pov" ]; then
      printf 'povray reflective spp=1 t=%s ' "$t" >>"$log"
      (cd "$pov_dir" && povray +Ireflective.pov +O"$out/p.png" +W1280 +H720 -D -V +FN File_Gamma=sRGB -A +WT"$t" 2>&1) \
        | grep -E "Trace Time|CPU-seconds total" | tail -2 | tr '\n' ' ' >>"$log"
      echo >>"$log"
    fi
  done
done
python3 - "$log" <<'PY'
import re, statistics, sys
rows = {}
for line in open(sys.argv[1]):
    key = " ".join(line.split()[:4])
    if line.startswith("quadray"):
        wall = float(re.search(r"rays in ([\d.]+) s", line).group(1))
        cpu = float(re.search(r"render CPU ([\d.]+) s", line).group(1))
        mr = float(re.search(r"\(([\d.]+) Mrays/s\)", line).group(1))
    else:
        wall = float(re.search(r"Trace Time:.*\(([\d.]+) seconds\)", line).group(1))
        cpu = float(re.search(r"with ([\d.]+) CPU-seconds", line).group(1))
        mr = float("nan")
    rows.setdefault(key, []).append((wall, cpu, mr))
print("| run | wall s (median) | CPU s (median) | Mrays/s (median) | n |")
print("|---|---|---|---|---|")
for k, v in rows.items():
    med = lambda i: statistics.median(x[i] for x in v)
    print(f"| {k} | {med(0):.3f} | {med(1):.3f} | {med(2):.2f} | {len(v)} |")
q = [x[1] for x in rows.get("quadray reflective spp=1 t=1", [])]
p = [x[1] for x in rows.get("povray reflective spp=1 t=1", [])]
if q and p:
    print(f"\nreflective, 1 thread: POV-Ray trace CPU-s / quadray render CPU-s = {statistics.median(p)/statistics.median(q):.2f}")
PY
