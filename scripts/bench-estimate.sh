#!/usr/bin/env bash
# The image-error estimate against the truth: each scene rendered with --target-error at several
# targets and seeds (480x270, one thread), its reported "estimated image error" set against the
# sRGB RMSE from its own 1024-spp reference (`quadray compare`, the "(sRGB)" figure). Writes
# docs/image-error/estimate.md (one row per render and a summary) and estimate.svg (estimate
# against truth, log-log, with the ±25% band).
#   scripts/bench-estimate.sh [SEEDS="1 2 3 4 5"] [TARGETS="0.002 0.001 0.0005"] [SCENES="defense reflective grid mesh"]
set -euo pipefail
cd "$(dirname "$0")/.."
seeds=${1:-"1 2 3 4 5"}
targets=${2:-"0.002 0.001 0.0005"}
scenes=${3:-"defense reflective grid mesh"}
cargo build --release -q -p quadray-cli
bin=target/release/quadray
out=docs/image-error
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
zstd -q -d -f ../shared/assets/meshes/obvhs_kitchen/kitchen.obj.zst -o "$tmp/kitchen.obj"
python3 scripts/harness_scenes.py ../shared/peers/povray/scenes.json "$tmp"
rows=$tmp/rows.txt
: >"$rows"
for name in $scenes; do
  case $name in
    defense | reflective) scene=scenes/$name.toml ;;
    grid | mesh) scene=$tmp/$name.toml ;;
    *) echo "unknown scene $name" >&2; exit 2 ;;
  esac
  echo "== $name: reference" >&2
  "$bin" render "$scene" --res 480x270 --spp 1024 --seed 1000 -o "$tmp/$name-ref.exr" 2>/dev/null
  for target in $targets; do
    for seed in $seeds; do
      log=$("$bin" render "$scene" --res 480x270 --target-error "$target" --seed "$seed" -t 1 \
        --stats -o "$tmp/test.exr" 2>&1)
      estimate=$(grep -oE "estimated image error [0-9.e+-]+" <<<"$log" | awk '{print $4}')
      cpu=$(grep -oE "render CPU [0-9.]+" <<<"$log" | awk '{print $3}')
      spp=$(grep -oE "[0-9.]+ spp mean" <<<"$log" | awk '{print $1}')
      # compare exits non-zero when the images differ beyond its thresholds: only its RMSE is
      # wanted here.
      truth=$({ "$bin" compare "$tmp/test.exr" "$tmp/$name-ref.exr" 2>&1 || true; } |
        grep -oE "[0-9.e+-]+ \(sRGB\)" | awk '{print $1}')
      echo "$name $target $seed $cpu $spp $estimate $truth" | tee -a "$rows" >&2
    done
  done
done
python3 - "$rows" "$out" <<'EOF'
import math, sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
out = sys.argv[2]
md = ["Estimated against true image error (`scripts/bench-estimate.sh`): 480x270, one thread, "
      "`--target-error T --seed S`; the truth is the sRGB RMSE against the scene's own 1024-spp "
      "reference (seed 1000).", "",
      "| scene | target | seed | CPU s | mean spp | estimated | true | estimate / true |",
      "|---|---:|---:|---:|---:|---:|---:|---:|"]
ratios = {}
for name, target, seed, cpu, spp, est, true in rows:
    r = float(est) / float(true)
    ratios.setdefault(name, []).append(r)
    md.append(f"| {name} | {target} | {seed} | {cpu} | {spp} | {est} | {true} | {r:.2f} |")
md += ["", "| scene | renders | within ±25% | median ratio | range |", "|---|---:|---:|---:|---|"]
every = []
for name, rs in ratios.items():
    every += rs
    inside = sum(0.75 <= r <= 1.25 for r in rs)
    s = sorted(rs)
    md.append(f"| {name} | {len(rs)} | {inside} | {s[len(s)//2]:.2f} | {s[0]:.2f}–{s[-1]:.2f} |")
s = sorted(every)
md.append(f"| all | {len(s)} | {sum(0.75 <= r <= 1.25 for r in s)} | {s[len(s)//2]:.2f} | {s[0]:.2f}–{s[-1]:.2f} |")
open(f"{out}/estimate.md", "w").write("\n".join(md) + "\n")
# The plot: log-log, estimate against truth, the diagonal and the ±25% band.
pts = [(float(t), max(float(e), 1e-6), n) for n, _, _, _, _, e, t in rows]
lo = min(min(p[0], p[1]) for p in pts) / 1.5
hi = max(max(p[0], p[1]) for p in pts) * 1.5
W, H, M = 640, 640, 70
def xy(t, e):
    f = lambda v: (math.log(v) - math.log(lo)) / (math.log(hi) - math.log(lo))
    return M + f(t) * (W - 2 * M), H - M - f(e) * (H - 2 * M)
colours = {"defense": "#1f77b4", "reflective": "#2ca02c", "grid": "#ff7f0e", "mesh": "#d62728"}
svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="13">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<rect x="{M}" y="{M}" width="{W-2*M}" height="{H-2*M}" fill="none" stroke="black"/>',
       f'<clipPath id="frame"><rect x="{M}" y="{M}" width="{W-2*M}" height="{H-2*M}"/></clipPath>']
for k, dash in [(1.0, ""), (1.25, ' stroke-dasharray="4 4"'), (0.75, ' stroke-dasharray="4 4"')]:
    (x0, y0), (x1, y1) = xy(lo, lo * k), xy(hi, hi * k)
    svg.append(f'<line x1="{x0:.1f}" y1="{y0:.1f}" x2="{x1:.1f}" y2="{y1:.1f}" stroke="grey" clip-path="url(#frame)"{dash}/>')
decade = 10 ** math.floor(math.log10(lo))
while decade <= hi:
    for m in (1, 2, 5):
        v = decade * m
        if lo <= v <= hi:
            x, _ = xy(v, lo); _, y = xy(lo, v)
            svg.append(f'<text x="{x:.1f}" y="{H-M+18}" text-anchor="middle">{v:g}</text>')
            svg.append(f'<text x="{M-6}" y="{y+4:.1f}" text-anchor="end">{v:g}</text>')
    decade *= 10
for t, e, n in pts:
    x, y = xy(t, e)
    svg.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="4" fill="{colours.get(n, "black")}"/>')
for i, (n, c) in enumerate(colours.items()):
    svg.append(f'<circle cx="{M+14}" cy="{M+16+18*i}" r="4" fill="{c}"/><text x="{M+24}" y="{M+20+18*i}">{n}</text>')
svg.append(f'<text x="{W/2}" y="{H-20}" text-anchor="middle">true sRGB RMSE against a 1024-spp reference</text>')
svg.append(f'<text x="18" y="{H/2}" text-anchor="middle" transform="rotate(-90 18 {H/2})">estimated image error (the render\'s report)</text>')
svg.append(f'<text x="{W/2}" y="40" text-anchor="middle" font-size="15">Estimated against true image error, 480x270 (diagonal and ±25%)</text>')
svg.append('</svg>')
open(f"{out}/estimate.svg", "w").write("\n".join(svg) + "\n")
print("\n".join(md))
EOF
