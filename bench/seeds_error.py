#!/usr/bin/env python3
"""Error per sample and equal-error efficiency of one `spt render` configuration, from a few
renders with different seeds: against a reference where there is one (relMSE, as
bench/compare_error.py defines it), else from pairs of independent renders, which needs
no reference:

    relVar = mean over pixel-channels of (a - b)^2 / (m^2 + 1e-2) / 2

where a, b are the renders of one pair and m the mean of the *other* renders (independent
of the pair, so a firefly in a or b is not divided by itself). For an unbiased renderer the
expected squared difference of two independent renders is twice one render's variance,
so relVar estimates its relMSE, up to m's own noise in the denominator: compare
configurations by it, measured the same way. Prints the median sampling time `spt render`
reports, the error (and its spread over the images or pairs) and the efficiency
1 / (error x time); compare two configurations by running them one after the other,
alternately.

Usage (from the repository root, after `cargo build --release -p cli`):

    python3 bench/seeds_error.py [--spt target/release/spt] [--spp 64] [--seeds 5,6,7]
        [--reference REF.exr] SCENE [spt render flags ...]

The render is 256 x 256, hero mode, zsobol, 2 threads unless the flags say otherwise (the
later flag wins). Without --reference give an even number of seeds, at least four
(default 11,12,13,14). E.g. the Cornell box against the shared reference, Russian
roulette's scale 1 against 3:

    for s in 1 3; do python3 bench/seeds_error.py --spp 64 \\
      --reference ../shared/refs/cornell-box-original/cornell-box-original_spectral_256_4096spp.exr \\
      ../shared/scenes/cornell-box/CornellBox-Original-fixed.obj --eye 0,1,3.9 --center 0,1,0 \\
      --fov 39.3077 --rr-depth 5 --rr-scale $s; done
"""
import argparse, os, statistics, sys, tempfile

import numpy as np

from compare_error import read_exr, rel_mse, render_timed

DEFAULTS = ["--width", "256", "--height", "256", "--spectral", "hero", "--sampler", "zsobol", "--threads", "2"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], allow_abbrev=False)
    ap.add_argument("--spt", default="target/release/spt")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seeds", default=None, help="comma-separated (default 5,6,7 with --reference, else 11,12,13,14)")
    ap.add_argument("--reference", help="converged EXR of the same view")
    ap.add_argument("scene")
    ap.add_argument("flags", nargs=argparse.REMAINDER, help="spt render flags")
    a = ap.parse_args()
    seeds = [int(s) for s in (a.seeds or ("5,6,7" if a.reference else "11,12,13,14")).split(",")]
    if not a.reference and (len(seeds) % 2 or len(seeds) < 4):
        sys.exit("without --reference, give an even number of seeds, at least four (renders are compared in pairs)")
    times, images = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in seeds:
            out = os.path.join(tmp, f"{seed}.exr")
            cmd = [a.spt, "render", a.scene, *DEFAULTS, *a.flags, "--spp", str(a.spp), "--seed", str(seed), "-o", out]
            t, img = render_timed(cmd, out)
            times.append(t)
            images.append(img)
    if a.reference:
        ref = read_exr(a.reference)
        if ref.shape != images[0].shape:
            sys.exit(f"{a.reference}: shape {ref.shape} differs from the renders' {images[0].shape}")
        errors, kind = [rel_mse(img, ref) for img in images], "relMSE"
    else:
        errors = []
        for i in range(0, len(images), 2):
            others = np.mean([img for k, img in enumerate(images) if k not in (i, i + 1)], axis=0)
            errors.append(float(np.mean((images[i] - images[i + 1]) ** 2 / (others**2 + 1e-2)) / 2))
        kind = "relVar"
    error, t = float(np.mean(errors)), statistics.median(times)
    print(f"{os.path.basename(a.scene)} {' '.join(a.flags)}: {t:.3f} s, {kind} {error:.5f} "
          f"(from {min(errors):.5f} to {max(errors):.5f}), efficiency {1 / (error * t):.1f}")


if __name__ == "__main__":
    main()
