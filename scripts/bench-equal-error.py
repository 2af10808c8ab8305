#!/usr/bin/env python3
"""Adaptive sampling's CPU time against uniform sampling's at the same true image error.

For one scene at 480x270 on one thread: a 1024-spp reference (seed 1000), uniform renders at 8,
16, 32 and 64 spp and image-rule renders at targets 0.002, 0.001 and 0.0005 (seed 0), each the
median CPU time of three runs; the true error of each is the sRGB RMSE against the reference
(`quadray compare`, the "(sRGB)" figure). An adaptive render's ratio is its CPU time over the
uniform time at its true error, interpolated log-log between the uniform rows (extrapolated past
their ends). docs/sampling.md reports these ratios.

    scripts/bench-equal-error.py SCENE [EXTRA ADAPTIVE ARGS...]
    QUADRAY=path/to/quadray scripts/bench-equal-error.py scenes/defense.toml --min-spp 4

The binary defaults to target/release/quadray (build it first: `cargo build --release -p
quadray-cli`).
"""
import math
import os
import re
import subprocess
import sys
import tempfile

RES = "480x270"
UNIFORM_SPP = [8, 16, 32, 64]
TARGETS = ["0.002", "0.001", "0.0005"]


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    scene, extra = sys.argv[1], sys.argv[2:]
    quadray = os.environ.get("QUADRAY", "target/release/quadray")
    with tempfile.TemporaryDirectory() as tmp:
        reference = os.path.join(tmp, "reference.exr")
        image = os.path.join(tmp, "image.exr")

        def render(args):
            """Median render CPU seconds of three runs, and the mean spp of the last."""
            cpus, spp = [], None
            for _ in range(3):
                log = subprocess.run(
                    [quadray, "render", scene, "--res", RES, "-t", "1", "--stats", "-o", image]
                    + args,
                    capture_output=True,
                    text=True,
                    check=True,
                ).stderr
                cpus.append(float(re.search(r"render CPU ([0-9.]+)", log).group(1)))
                found = re.search(r"([0-9.]+) spp mean", log)
                spp = found.group(1) if found else None
            return sorted(cpus)[1], spp

        def true_error():
            # `compare` exits non-zero when the images differ beyond its thresholds; only its
            # RMSE is wanted here.
            out = subprocess.run(
                [quadray, "compare", image, reference], capture_output=True, text=True
            )
            return float(re.search(r"([0-9.e+-]+) \(sRGB\)", out.stdout + out.stderr).group(1))

        subprocess.run(
            [quadray, "render", scene, "--res", RES, "--spp", "1024", "--seed", "1000", "-o",
             reference],
            capture_output=True,
            check=True,
        )
        uniform = []
        for spp in UNIFORM_SPP:
            cpu, _ = render(["--spp", str(spp)])
            uniform.append((spp, cpu, true_error()))
        print(f"{scene} uniform: "
              + ", ".join(f"{s} spp {c:.3f} s {e:.2e}" for s, c, e in uniform))

        def uniform_cpu_at(error):
            rows = sorted(uniform, key=lambda r: -r[2])  # falling error
            pairs = list(zip(rows, rows[1:]))
            for i, ((_, c0, e0), (_, c1, e1)) in enumerate(pairs):
                first, last = i == 0, i == len(pairs) - 1
                if e1 <= error <= e0 or (first and error > e0) or (last and error < e1):
                    f = (math.log(error) - math.log(e0)) / (math.log(e1) - math.log(e0))
                    return math.exp(math.log(c0) + f * (math.log(c1) - math.log(c0)))
            return float("nan")

        for target in TARGETS:
            cpu, spp = render(["--target-error", target, "--seed", "0"] + extra)
            error = true_error()
            print(f"{scene} target {target} {' '.join(extra)}: {cpu:.3f} s, {spp} spp, "
                  f"true error {error:.2e}, {cpu / uniform_cpu_at(error):.2f}x uniform's time")


if __name__ == "__main__":
    main()
