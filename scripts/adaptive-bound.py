#!/usr/bin/env python3
"""How far adaptive sampling could go on one scene: bounds from per-pixel errors measured on
independent renders, against what `quadray render --target-error` reaches.

Every pixel of a render with `--target-error 1e9 --min-spp n` takes exactly the first n samples of
its own progressive sequence, each filtered at the footprint of the default `--max-spp` (1024), and
no pixel refines (no relative error is above 1e9): the samples an adaptive render gives it at count
n. From S such renders with independent sample sets (`--seed`) at n = 8..512, the squared error of
each pixel at each n against a 1024-spp reference is known S times over. Choosing each pixel's n
from the first S-2 renders and scoring the choice on the last 2 (so that luck in the choice is not
counted as skill) gives the sample budget, as a fraction of uniform 64 spp, at which each rule
matches the linear RMSE of uniform 64-spp renders (`--spp 64`) with the scoring sample sets:

- oracle: each pixel's n minimises n + mu * error(n), the allocation that minimises the total
  squared error for its total samples (the best any rule can do with that knowledge);
- threshold rule: each pixel's n is the smallest whose relative display error (the root of its
  squared display error over max(display value, 0.1), the quantity the sampler compares with
  its target) is below one threshold for all pixels: the sampler's own stopping rule, with the
  pixel's error known instead of estimated from its samples;
Counts start at 8, the default first round: previews from 2 or 4 are not in the bound.

- the sampler itself, at a few targets (mean spp and linear RMSE; its CPU time is another matter:
  the pixels it refines cost more rays per sample than the average pixel).

Needs numpy and OpenEXR (pip install numpy OpenEXR). Renders are kept in --work and reused.
    scripts/adaptive-bound.py [--scene scenes/defense.toml] [--seeds 8] [--work /tmp/bound]
"""
import argparse
import os
import subprocess
import sys

import numpy as np
import OpenEXR

COUNTS = [8, 16, 32, 64, 128, 256, 512]
UNIFORM = COUNTS.index(64)


def render(args, out, *extra):
    """Renders the scene into `out` unless it is there already."""
    if os.path.exists(out):
        return
    cmd = [args.bin, "render", args.scene, "--res", args.res, "-o", out, *extra]
    subprocess.run(cmd, check=True, stderr=subprocess.DEVNULL)


def linear(path):
    """The beauty pass's linear RGB."""
    with OpenEXR.File(path) as f:
        channels = f.channels()
        key = next(k for k in channels if "Combined" in k or k in ("RGB", "RGBA"))
        return channels[key].pixels[..., :3].astype(np.float64)


def display(rgb):
    """The mean of the sRGB-encoded channels, clamped to [0, 1]."""
    x = np.clip(rgb, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055).mean(-1)


def threshold_counts(errors, kept_error, target_mse):
    """Per pixel, the index of the smallest count whose `errors` are at most a threshold, with the
    largest threshold that keeps the mean of `kept_error` at the chosen counts at `target_mse`."""
    low, high = 1e-16, 1e2
    feasible = np.full(errors.shape[1:], len(COUNTS) - 1)
    for _ in range(200):
        threshold = np.sqrt(low * high)
        below = errors <= threshold
        below[-1] = True
        choice = np.argmax(below, 0)
        if np.take_along_axis(kept_error, choice[None], 0)[0].mean() > target_mse:
            high = threshold
        else:
            low, feasible = threshold, choice
    return feasible


def oracle_counts(errors, kept_error, target_mse):
    """Per pixel, the index of the count minimising n + mu * error(n), with the smallest mu that
    keeps the mean of `kept_error` at the chosen counts at `target_mse`."""
    n = np.array(COUNTS, float)[:, None, None]
    low, high = 1e-3, 1e16
    feasible = np.full(errors.shape[1:], len(COUNTS) - 1)
    for _ in range(200):
        mu = np.sqrt(low * high)
        choice = np.argmin(n + mu * errors, 0)
        if np.take_along_axis(kept_error, choice[None], 0)[0].mean() > target_mse:
            low = mu
        else:
            high, feasible = mu, choice
    return feasible


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", default="scenes/defense.toml")
    p.add_argument("--res", default="480x270")
    p.add_argument("--seeds", type=int, default=8, help="independent render sets (at least 3)")
    p.add_argument("--targets", default="0.02,0.01,0.0075,0.005")
    p.add_argument("--bin", default="target/release/quadray")
    p.add_argument("--work", default="/tmp/adaptive-bound")
    args = p.parse_args()
    if args.seeds < 3:
        sys.exit("--seeds must be at least 3: the choice needs one set, the score two")
    os.makedirs(args.work, exist_ok=True)
    # Renders are cached under names that say the scene and resolution they are of.
    stem = f"{os.path.splitext(os.path.basename(args.scene))[0]}-{args.res}"
    work = lambda name: os.path.join(args.work, f"{stem}-{name}")

    render(args, work("reference.exr"), "--spp", "1024", "--seed", "1")
    reference = linear(work("reference.exr"))
    reference_display = display(reference)
    seeds = range(11, 11 + args.seeds)
    squared, squared_display = [], []
    for seed in seeds:
        per_count, per_count_display = [], []
        for n in COUNTS:
            out = work(f"prefix-{seed}-{n}.exr")
            render(args, out, "--target-error", "1e9", "--min-spp", str(n), "--seed", str(seed))
            image = linear(out)
            per_count.append(((image - reference) ** 2).mean(-1))
            per_count_display.append((display(image) - reference_display) ** 2)
        squared.append(per_count)
        squared_display.append(per_count_display)
    squared = np.array(squared)  # seed, count, y, x
    squared_display = np.array(squared_display)

    chosen, scored = slice(0, args.seeds - 2), slice(args.seeds - 2, args.seeds)
    choose = squared[chosen].mean(0)
    score = squared[scored].mean(0)
    relative = np.sqrt(squared_display[chosen].mean(0)) / np.maximum(reference_display, 0.1)
    uniform = []
    for seed in list(seeds)[scored]:
        out = work(f"uniform-{seed}-64.exr")
        render(args, out, "--spp", "64", "--seed", str(seed))
        uniform.append(((linear(out) - reference) ** 2).mean())
    uniform_mse = np.mean(uniform)
    print(f"{args.scene} at {args.res}: uniform 64 spp, linear RMSE {np.sqrt(uniform_mse):.3e} "
          f"(prefixes of 64: {np.sqrt(score[UNIFORM].mean()):.3e})")
    print(f"choice from {args.seeds - 2} sample sets, scored on 2; samples as a fraction of 64 spp "
          "at uniform 64's linear RMSE:")
    for name, choice in [
        ("oracle (least samples for the error)", oracle_counts(choose, score, uniform_mse)),
        ("threshold on relative display error", threshold_counts(relative, score, uniform_mse)),
        ("threshold on linear error", threshold_counts(choose, score, uniform_mse)),
    ]:
        counts = np.array(COUNTS)[choice]
        print(f"  {name}: {counts.mean() / 64:.3f}")

    print("the sampler (seeds 11, 12): mean spp / 64, linear RMSE / uniform 64's")
    curve = []
    for target in args.targets.split(","):
        spp, mse = [], []
        for seed in (11, 12):
            out = work(f"adaptive-{seed}-{target}.exr")
            render(args, out, "--target-error", target, "--seed", str(seed), "--aov",
                   "sample-count")
            with OpenEXR.File(out) as f:
                count = next(v for k, v in f.channels().items() if "Sample Count" in k).pixels
            spp.append(count.mean())
            mse.append(((linear(out) - reference) ** 2).mean())
        share, ratio = np.mean(spp) / 64, np.sqrt(np.mean(mse) / uniform_mse)
        curve.append((share, ratio))
        print(f"  target {target}: {share:.3f} of the samples, RMSE {ratio:.3f}x")
    # Log-log interpolation between the two targets around uniform 64's error.
    curve.sort()
    brackets = [(a, b) for a, b in zip(curve, curve[1:]) if a[1] >= 1.0 >= b[1]]
    if not brackets:
        print("  no two targets bracket uniform 64's RMSE: widen --targets")
    for (s0, r0), (s1, r1) in brackets[:1]:
        f = np.log(r0) / np.log(r0 / r1)
        share = s0 * (s1 / s0) ** f
        print(f"  at uniform 64's RMSE (interpolated): {share:.3f} of the samples")


if __name__ == "__main__":
    main()
