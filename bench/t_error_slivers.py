#!/usr/bin/env python3
"""Where our hits' t is imprecise: how many closest hits are off by more than 1e-6
(relative, against the float64 plane of the hit triangle), how many of those lie on
slivers, triangles whose longest edge^2 exceeds S times twice their area, how many are
at grazing incidence and how many lie fairly near the ray origin relative to its
coordinates.

Reads a ray-set folder of bench/embree_rays.py / `spt rays export` and the hits file an
`spt rays trace DIR` run wrote there (<set>.bvh8.hits by default). Written for the sliver
rule of the sixth session (SLIVER = 30 in crates/bvh/src/wide/collapse.rs, since replaced:
every closest hit's t is now recomputed in f64); run it on the hits of `spt rays trace DIR
--raw-t` to see where the f32 test's own t is imprecise.

Usage (from the repository root):
    target/release/spt rays trace bench/embree/build/rays/sponza --passes 1
    python3 bench/t_error_slivers.py bench/embree/build/rays/sponza [--hits bvh8] [--sets primary,diffuse]
"""
import argparse

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir")
    ap.add_argument("--hits", default="bvh8", help="hits file infix: <set>.<HITS>.hits")
    ap.add_argument("--sets", default="primary,diffuse")
    ap.add_argument("--bound", type=float, default=1e-6)
    a = ap.parse_args()
    tris = np.fromfile(f"{a.dir}/triangles.f32", np.float32).reshape(-1, 3, 3).astype(np.float64)
    e0, e1, e2 = tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 1], tris[:, 0] - tris[:, 2]
    n_all = np.cross(e0, -e2)
    longest = np.max([np.einsum("ij,ij->i", e, e) for e in (e0, e1, e2)], axis=0)
    ratio = longest / np.maximum(np.linalg.norm(n_all, axis=1), 1e-300)
    for s in a.sets.split(","):
        rays = np.fromfile(f"{a.dir}/{s}.rays", np.float32).reshape(-1, 8).astype(np.float64)
        h = np.fromfile(f"{a.dir}/{s}.{a.hits}.hits", np.uint32).reshape(-1, 4)
        idx = np.nonzero(h[:, 0] != 0xFFFFFFFF)[0]
        prim = h[idx, 0].astype(np.int64)
        t = h[idx, 1].view(np.float32).astype(np.float64)
        o, d, n = rays[idx, 0:3], rays[idx, 3:6], n_all[prim]
        t64 = np.einsum("ij,ij->i", n, tris[prim, 0] - o) / np.einsum("ij,ij->i", n, d)
        with np.errstate(divide="ignore", invalid="ignore"):
            err = np.abs(t - t64) / np.abs(t64)
        bad = err > a.bound
        r = ratio[prim]
        print(f"{s}: {len(idx)} hits, {bad.sum()} above {a.bound:g} (max {np.nanmax(err):.2e})")
        for S in (10, 30, 100):
            on = bad & (r > S)
            print(f"  on slivers above {S}: {on.sum()} of them ({100 * on.sum() / max(bad.sum(), 1):.1f} %); "
                  f"slivers take {100 * (r > S).mean():.2f} % of all hits")
        # Grazing incidence: the ray within about 3 degrees of the triangle's plane.
        cos = np.abs(np.einsum("ij,ij->i", n, d)) / (np.linalg.norm(n, axis=1) * np.linalg.norm(d, axis=1))
        print(f"  at grazing incidence (|cos| < 0.05): {(bad & (cos < 0.05)).sum()} of them")
        # Near the origin relative to its coordinates, but beyond traverse.rs's REFINE_BELOW (1/8).
        ratio_o = t64 * np.linalg.norm(d, axis=1) / np.abs(o).max(axis=1)
        mid = (ratio_o >= 0.125) & (ratio_o < 0.5)
        print(f"  at 1/8 to 1/2 of the origin's largest coordinate: {(bad & mid).sum()} of them")


if __name__ == "__main__":
    main()
