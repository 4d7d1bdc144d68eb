#!/usr/bin/env python3
"""Error per sample and equal-error efficiency of one `spt render` configuration, from a few
renders with different seeds: against a reference where there is one (relMSE, as
bench/compare_error.py defines it), else from pairs of independent renders, which needs
no reference:

    relVar = mean over pixel-channels of (a - b)^2 / (m^2 + 1e-2) / 2,   m = (a + b) / 2

(for an unbiased renderer the expected squared difference of two independent renders is
twice one render's variance, so relVar estimates its relMSE). Prints the median sampling
time `spt render` reports, the error and the efficiency 1 / (error x time); compare two
configurations by running them one after the other, alternately.

Usage (from the repository root, after `cargo build --release -p cli`):

    python3 bench/seeds_error.py [--spt target/release/spt] [--spp 64] [--seeds 5,6,7]
        [--reference REF.exr] SCENE [spt render flags ...]

The render is 256 x 256, hero mode, zsobol, 2 threads unless the flags say otherwise (the
later flag wins). Without --reference the number of seeds must be even (consecutive pairs).
E.g. the Cornell box against the shared reference, Russian roulette's scale 1 against 3:

    for s in 1 3; do python3 bench/seeds_error.py --spp 64 \\
      --reference ../shared/refs/cornell-box-original/cornell-box-original_spectral_256_4096spp.exr \\
      ../shared/scenes/cornell-box/CornellBox-Original-fixed.obj --eye 0,1,3.9 --center 0,1,0 \\
      --fov 39.3077 --rr-depth 5 --rr-scale $s; done
"""
import argparse, os, re, statistics, subprocess, sys, tempfile

import numpy as np

from compare_error import read_exr, rel_mse

DEFAULTS = ["--width", "256", "--height", "256", "--spectral", "hero", "--sampler", "zsobol", "--threads", "2"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spt", default="target/release/spt")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seeds", default=None, help="comma-separated (default 5,6,7 with --reference, else 11,12,13,14)")
    ap.add_argument("--reference", help="converged EXR of the same view")
    ap.add_argument("scene")
    a, flags = ap.parse_known_args()
    seeds = [int(s) for s in (a.seeds or ("5,6,7" if a.reference else "11,12,13,14")).split(",")]
    if not a.reference and len(seeds) % 2:
        sys.exit("without --reference, give an even number of seeds (renders are compared in pairs)")
    times, images = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in seeds:
            out = os.path.join(tmp, f"{seed}.exr")
            cmd = [a.spt, "render", a.scene, *DEFAULTS, *flags, "--spp", str(a.spp), "--seed", str(seed), "-o", out]
            p = subprocess.run(cmd, capture_output=True, text=True)
            if p.returncode != 0:
                sys.exit(f"{' '.join(cmd)}: {p.stderr}")
            times.append(float(re.search(r"wrote .*?: ([0-9.]+) s,", p.stderr).group(1)))
            images.append(read_exr(out))
    if a.reference:
        ref = read_exr(a.reference)
        error, kind = float(np.mean([rel_mse(img, ref) for img in images])), "relMSE"
    else:
        pairs = [(images[i], images[i + 1]) for i in range(0, len(images), 2)]
        error = float(np.mean([np.mean((x - y) ** 2 / (((x + y) / 2) ** 2 + 1e-2)) / 2 for x, y in pairs]))
        kind = "relVar"
    t = statistics.median(times)
    print(f"{os.path.basename(a.scene)} {' '.join(flags)}: {t:.3f} s, {kind} {error:.5f}, efficiency {1 / (error * t):.1f}")


if __name__ == "__main__":
    main()
