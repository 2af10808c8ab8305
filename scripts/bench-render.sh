#!/usr/bin/env bash
# Render benchmark against POV-Ray 3.7 on the peer harness's scenes, interleaved in one run:
#   - `reflective`: scenes/reflective.toml, the hand port checked against POV-Ray's image;
#   - `grid` (ten clipped quadrics) and `mesh` (the 57k-triangle kitchen): converted at run time
#     from the harness's renderer-neutral ../shared/peers/povray/scenes.json (into a temp dir);
#   - `defense`: scenes/defense.toml, translated at run time by scenes/pov/toml2pov.py (the
#     translation scenes/pov/verify.sh checks the bundled scenes' images with).
# All at 1280x720, 1 sample per pixel, max trace level 8, on 1 and 2 threads. Reports medians over
# REPS runs of render wall time, CPU-seconds and Mrays/s, and POV-Ray / quadray CPU-time ratios.
#   scripts/bench-render.sh [REPS=5]      (POV-Ray: apt-get install povray; pairs skipped if absent)
# QUADRAY=path times that binary instead of building target/release/quadray (say the
# profile-guided target/pgo/quadray of scripts/build-pgo.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
reps=${1:-5}
if [ -z "${QUADRAY:-}" ]; then
  cargo build --release -q -p quadray-cli --features bench
fi
bin=${QUADRAY:-target/release/quadray}
harness=../shared/peers/povray
pov_dir=$harness/pov
out=$(mktemp -d)
log=$out/log.txt

# The kitchen mesh, and quadray ports of the harness's grid and mesh scenes.
zstd -q -d -f ../shared/assets/meshes/obvhs_kitchen/kitchen.obj.zst -o "$out/kitchen.obj"
python3 scripts/harness_scenes.py "$harness/scenes.json" "$out"
python3 scenes/pov/toml2pov.py scenes/defense.toml "$out/defense.pov" 1280 720

quadray_run() { # label, scene, threads
  printf 'quadray %s t=%s ' "$1" "$3" >>"$log"
  "$bin" render "$2" -o "$out/q.png" --res 1280x720 --spp 1 -t "$3" --stats 2>&1 | tr '\n' ' ' >>"$log"
  echo >>"$log"
}
pov_run() { # label, directory, pov file in it, threads
  if command -v povray >/dev/null && [ -f "$2/$3" ]; then
    printf 'povray %s t=%s ' "$1" "$4" >>"$log"
    (cd "$2" && povray +I"$3" +O"$out/p.png" +W1280 +H720 -D -V +FN File_Gamma=sRGB -A +WT"$4" 2>&1) \
      | grep -E "Trace Time|CPU-seconds total" | tail -2 | tr '\n' ' ' >>"$log"
    echo >>"$log"
  fi
}
for rep in $(seq "$reps"); do
  echo "round $rep (load $(cut -d' ' -f1 /proc/loadavg))" >&2
  for t in 1 2; do
    quadray_run defense scenes/defense.toml "$t"
    pov_run defense "$out" defense.pov "$t"
    quadray_run reflective scenes/reflective.toml "$t"
    pov_run reflective "$pov_dir" reflective.pov "$t"
    quadray_run grid "$out/grid.toml" "$t"
    pov_run grid "$pov_dir" grid.pov "$t"
    quadray_run mesh "$out/mesh.toml" "$t"
    pov_run mesh "$pov_dir" mesh.pov "$t"
  done
done
python3 - "$log" <<'PY'
import re, statistics, sys
rows = {}
for line in open(sys.argv[1]):
    key = " ".join(line.split()[:3])
    if line.startswith("quadray"):
        wall = float(re.search(r"rays in ([\d.]+) s", line).group(1))
        cpu = float(re.search(r"render CPU ([\d.]+) s", line).group(1))
        mr = float(re.search(r"\(([\d.]+) Mrays/s\)", line).group(1))
        # The BVH's path, then the path of the SIMD kernels (the four-ray quadric test, the
        # sample points), which analytic scenes take on AVX2 while their BVH runs the baseline.
        path = re.search(r"traversal (\S+),(?: kernels (\S+),)?", line)
        simd = path.group(1) + (f" / {path.group(2)}" if path.group(2) else "")
    else:
        wall = float(re.search(r"Trace Time:.*\(([\d.]+) seconds\)", line).group(1))
        cpu = float(re.search(r"with ([\d.]+) CPU-seconds", line).group(1))
        mr, simd = float("nan"), ""
    rows.setdefault(key, []).append((wall, cpu, mr, simd))
print("| run | wall s (median) | CPU s (median) | Mrays/s (median) | n | traversal / kernels |")
print("|---|---|---|---|---|---|")
for k, v in rows.items():
    med = lambda i: statistics.median(x[i] for x in v)
    print(f"| {k} | {med(0):.3f} | {med(1):.3f} | {med(2):.2f} | {len(v)} | {v[0][3]} |")
print()
for scene in ("defense", "reflective", "grid", "mesh"):
    for t in (1, 2):
        q = [x[1] for x in rows.get(f"quadray {scene} t={t}", [])]
        p = [x[1] for x in rows.get(f"povray {scene} t={t}", [])]
        if q and p:
            print(f"- {scene}, {t} thread(s): POV-Ray trace CPU-s / quadray render CPU-s = {statistics.median(p) / statistics.median(q):.2f}")
for scene in ("defense", "reflective", "grid", "mesh"):
    one = [x[0] for x in rows.get(f"quadray {scene} t=1", [])]
    two = [x[0] for x in rows.get(f"quadray {scene} t=2", [])]
    if one and two:
        print(f"- quadray {scene}: 2-thread wall-time scaling {statistics.median(one) / statistics.median(two):.2f}x")
PY
