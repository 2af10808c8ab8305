#!/usr/bin/env bash
# A profile-guided build of the `quadray` binary, an experiment and not the release build: an
# instrumented build renders a training set, rustc's LLVM tools merge the counts, and a second
# build lays out and inlines the code by them. The images are the same bit for bit (the
# optimiser's choices move code, not floating point). Measured (docs/performance.md, *Defense
# against POV-Ray, and five experiments*): analytic frames 5-12% faster, mesh frames 1-4% slower,
# the profile leaving the AVX2 node test out of line.
#
#   scripts/build-pgo.sh [CARGO BUILD OPTIONS...]     e.g. --features bench
#
# Writes target/pgo/quadray. Needs rustup's llvm-tools (`rustup component add llvm-tools`) for
# llvm-profdata of the compiler's own LLVM version. The training set is the bundled scenes but
# scenes/reflective.toml and scenes/defense.toml, which scripts/bench-render.sh times (so the
# speed figures are not measured on what the build was trained on), and a generated mesh of 82k
# triangles. Two builds in target dirs of their own (target/pgo-gen, target/pgo-use), so
# target/release stays as it is: about 6 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
sysroot=$(rustc --print sysroot)
host=$(rustc -vV | sed -n 's/^host: //p')
profdata=$sysroot/lib/rustlib/$host/bin/llvm-profdata
[ -x "$profdata" ] || {
  echo "error: $profdata not found; install it with: rustup component add llvm-tools" >&2
  exit 1
}
data=$(mktemp -d)
work=$(mktemp -d)
trap 'rm -rf "$data" "$work"' EXIT

RUSTFLAGS="-Cprofile-generate=$data" CARGO_TARGET_DIR=target/pgo-gen \
  cargo build --release -q -p quadray-cli "$@"
trainee=target/pgo-gen/release/quadray
for scene in scenes/*.toml scenes/*.gltf; do
  case $(basename "$scene") in reflective.toml | defense.toml) continue ;; esac
  "$trainee" render "$scene" --res 320x180 -t 2 -q -o "$work/image.exr"
done
# A mesh of 82k triangles (the bundled meshes are small): a bumpy sphere on a floor, lit and
# unlit, so the mesh traversal's hot loops are trained as the big meshes run them.
python3 - "$work" <<'PY'
import math, sys
work = sys.argv[1]
t = (1 + 5 ** 0.5) / 2
verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9),
         (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
for _ in range(6):
    mid = {}
    def middle(a, b):
        key = (min(a, b), max(a, b))
        if key not in mid:
            verts.append(tuple((p + q) / 2 for p, q in zip(verts[a], verts[b])))
            mid[key] = len(verts) - 1
        return mid[key]
    faces = [f for a, b, c in faces for f in ((a, middle(a, b), middle(c, a)),
             (b, middle(b, c), middle(a, b)), (c, middle(c, a), middle(b, c)),
             (middle(a, b), middle(b, c), middle(c, a)))]
with open(f"{work}/bumps.obj", "w") as out:
    for v in verts:
        n = math.sqrt(sum(x * x for x in v))
        r = 1 + 0.08 * math.sin(9 * v[0] / n) * math.sin(11 * v[1] / n) * math.sin(7 * v[2] / n)
        out.write("v %.6f %.6f %.6f\n" % tuple(x / n * r for x in v))
    out.writelines("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in faces)
for name, lights in (("lit", True), ("unlit", False)):
    with open(f"{work}/{name}.toml", "w") as out:
        out.write('version = 1\n[camera]\nfrom = [3.0, -3.5, 1.8]\nto = [0.0, 0.0, 0.9]\nvfov = 45\n'
                  '[render]\nresolution = [640, 360]\nspp = 1\n'
                  '[[material]]\nname = "grey"\ncolor = [0.7, 0.7, 0.7]\n'
                  '[[mesh]]\npath = "bumps.obj"\nmaterial = "grey"\n'
                  'transform = { translate = [0, 0, 1] }\n'
                  '[[plane]]\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\nmaterial = "grey"\n')
        if lights:
            out.write('[[light]]\ntype = "point"\nposition = [4.0, -5.0, 7.0]\nintensity = 60\n'
                      '[[light]]\ntype = "point"\nposition = [-3.0, -4.0, 6.0]\nintensity = 40\n')
PY
for scene in lit unlit; do
  "$trainee" render "$work/$scene.toml" -t 2 -q -o "$work/image.png"
done
# The adaptive sampler's rounds, pilot and audit, and an image with passes.
"$trainee" render scenes/mirrors.toml --res 320x180 --target-error 0.002 -t 2 -q -o "$work/image.png"
"$trainee" render scenes/obj-mesh.toml --res 320x180 --aov depth,normal,albedo,object-id -t 2 -q \
  -o "$work/image.exr"
"$profdata" merge -o "$work/merged.profdata" "$data"

RUSTFLAGS="-Cprofile-use=$work/merged.profdata" CARGO_TARGET_DIR=target/pgo-use \
  cargo build --release -q -p quadray-cli "$@"
mkdir -p target/pgo
cp target/pgo-use/release/quadray target/pgo/quadray
echo "wrote target/pgo/quadray"
