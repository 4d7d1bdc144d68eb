#!/usr/bin/env python3
"""Test stand-in for `spt rays export` / `spt rays trace`, to exercise ../embree_rays.py
before (or without) the Rust side. NOT a benchmark: tracing is brute force in numpy.

  fake_spt.py rays export SCENE --out DIR [--width W --height H] [--eye x,y,z
                          --center x,y,z] [--subdivide K] [--seed S]
      SCENE is ignored. What is written depends on $FAKE_SPT_EXPORT:
        tiny (default)  a hand-written set: 6 triangles, 12 primary/diffuse and 8 shadow
                        rays (hits, misses, tmin/tmax clipping, an unnormalised direction,
                        a ray through a shared edge, back faces)
        soup:N          N random small triangles in [-1,1]^3 and W*H rays per set
                        (primary: pinhole grid from z=-3; diffuse: random origin in the
                        box, random direction; shadow: segments between random points)
  fake_spt.py rays trace DIR [--threads T] [--passes P] [--bvh-width 4|8|auto]
      float64 Moller-Trumbore brute force over all triangles (refuses more than 2e8
      ray-triangle tests per set); writes DIR/<set>.<accel>.hits (auto -> bvh8) and prints
      the same JSON line as the real tracers. $FAKE_SPT_CORRUPT=K corrupts the first K
      primary records on purpose (even ray index -> claims a miss, odd -> claims the
      next triangle) so the driver's "who is right" bookkeeping can be checked.

The ray-set format is described in ../embree_rays.py.
"""
import argparse, json, os, sys, time

import numpy as np

MISS = 0xFFFFFFFF
HIT = np.dtype([("prim", "<u4"), ("t", "<f4"), ("u", "<f4"), ("v", "<f4")])


def rays_array(rows):
    return np.asarray(rows, dtype=np.float32).reshape(-1, 8)


def tiny_set():
    inf = np.inf
    tris = np.array([
        [0, 0, 0, 1, 0, 0, 0, 1, 0],        # 0: lower-left half of the unit square, z=0
        [1, 0, 0, 1, 1, 0, 0, 1, 0],        # 1: upper-right half (shares the x+y=1 edge)
        [0, 0, 1, 1, 0, 1, 0, 1, 1],        # 2: copy of 0 lifted to z=1
        [2, 0, 0, 3, 0, 0, 2, 0, 1],        # 3: vertical triangle in the y=0 plane
        [-1, -1, 5, 4, -1, 5, -1, 4, 5],    # 4: large triangle at z=5
        [10, 10, 10, 11, 10, 10, 10, 11, 10],  # 5: far away, never hit
    ], dtype=np.float32)
    primary = rays_array([
        [.25, .25, -1, 0, 0, 1, 0, inf],       # -> 0 at t=1
        [.75, .75, -1, 0, 0, 1, 0, inf],       # -> 1 at t=1
        [.25, .25, 2, 0, 0, -1, 0, inf],       # -> 2 at t=1 (0 behind it)
        [5, 5, -1, 0, 0, 1, 0, inf],           # miss
        [.25, .25, -1, 0, 0, 1, 0, .5],        # tmax stops before 0: miss
        [.25, .25, -1, 0, 0, 1, 1.5, inf],     # tmin skips 0 -> 2 at t=2
        [.5, .5, -1, 0, 0, 1, 0, inf],         # on the shared edge: 0 or 1 at t=1
        [.25, .25, .5, 0, 0, -1, 0, inf],      # back face of 0 at t=.5
        [.25, .25, -1, 0, 0, 2, 0, inf],       # unnormalised direction -> 0 at t=.5
        [2.2, -1, .2, 0, 1, 0, 0, inf],        # -> 3 at t=1
        [.1, .1, -1, .2, .2, 6, 0, inf],       # oblique, through 0 then 2 -> 0
        [0, 0, 4, 0, 0, 1, 0, inf],            # -> 4 at t=1
    ])
    diffuse = primary[::-1].copy()
    diffuse[:, 6] = np.where(diffuse[:, 6] == 0, 1e-4, diffuse[:, 6])
    def seg(p, q):
        p = np.asarray(p, np.float32); q = np.asarray(q, np.float32)
        return list(p) + list(q - p) + [1e-4, 1 - 1e-4]
    shadow = rays_array([
        seg([.25, .25, -1], [.25, .25, .5]),   # blocked by 0
        seg([.25, .25, -1], [.25, .25, -.1]),  # free
        seg([5, 5, -1], [5, 5, 3]),            # free
        seg([.25, .25, -1], [.25, .25, 0]),    # ends on 0: free (tmax = 1-1e-4)
        seg([.25, .25, 0], [.25, .25, 2]),     # starts on 0, crosses 2: blocked
        seg([.75, .75, .5], [.75, .75, -.5]),  # through 1: blocked
        seg([2.2, -1, .2], [2.2, -.5, .2]),    # stops before 3: free
        seg([0, 0, 4], [0, 0, 6]),             # through 4: blocked
    ])
    return tris, {"primary": primary, "diffuse": diffuse, "shadow": shadow}


def soup_set(ntri, nrays, seed):
    rng = np.random.default_rng(seed)
    c = rng.uniform(-1, 1, (ntri, 1, 3))
    tris = (c + rng.normal(0, 0.02, (ntri, 3, 3))).reshape(ntri, 9).astype(np.float32)
    n = nrays
    side = int(np.ceil(np.sqrt(n)))
    k = np.arange(n)
    px = (k % side + 0.5) / side * 2 - 1
    py = (k // side + 0.5) / side * 2 - 1
    d = np.stack([px * 0.4, py * 0.4, np.ones(n)], 1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    primary = np.zeros((n, 8), np.float32)
    primary[:, 0:3] = [0, 0, -3]
    primary[:, 3:6] = d
    primary[:, 7] = np.inf
    diffuse = np.zeros((n, 8), np.float32)
    diffuse[:, 0:3] = rng.uniform(-1, 1, (n, 3))
    dd = rng.normal(size=(n, 3))
    diffuse[:, 3:6] = dd / np.linalg.norm(dd, axis=1, keepdims=True)
    diffuse[:, 6] = 1e-4
    diffuse[:, 7] = np.inf
    p = rng.uniform(-1, 1, (n, 3)); q = rng.uniform(-1, 1, (n, 3))
    shadow = np.zeros((n, 8), np.float32)
    shadow[:, 0:3] = p
    shadow[:, 3:6] = q - p
    shadow[:, 6] = 1e-4
    shadow[:, 7] = 1 - 1e-4
    return tris, {"primary": primary, "diffuse": diffuse, "shadow": shadow}


def export(a):
    mode = os.environ.get("FAKE_SPT_EXPORT", "tiny")
    if mode == "tiny":
        tris, sets = tiny_set()
    elif mode.startswith("soup:"):
        tris, sets = soup_set(int(mode[5:]), a.width * a.height, a.seed)
    else:
        sys.exit(f"fake_spt: unknown FAKE_SPT_EXPORT={mode!r}")
    os.makedirs(a.out, exist_ok=True)
    tris.astype("<f4").tofile(os.path.join(a.out, "triangles.f32"))
    for name, r in sets.items():
        r.astype("<f4").tofile(os.path.join(a.out, f"{name}.rays"))
    print(f"fake_spt: wrote {len(tris)} triangles, "
          + ", ".join(f"{len(r)} {k}" for k, r in sets.items()) + f" rays to {a.out}",
          file=sys.stderr)


def brute(tris, rays, any_hit):
    """float64 Moller-Trumbore against every triangle; closest (or any) hit per ray."""
    n, m = len(rays), len(tris)
    if n * m > 2e8:
        sys.exit(f"fake_spt: {n} rays x {m} triangles is too much for brute force")
    v0, v1, v2 = tris[:, 0:3], tris[:, 3:6], tris[:, 6:9]
    e1, e2 = v1 - v0, v2 - v0
    out = np.zeros(n, HIT)
    step = max(1, int(4e6 // max(m, 1)))
    for s in range(0, n, step):
        r = rays[s:s + step]
        o, d = r[:, None, 0:3], r[:, None, 3:6]
        p = np.cross(d, e2[None])
        det = np.einsum("rmk,mk->rm", p, e1)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            sv = o - v0[None]
            u = np.einsum("rmk,rmk->rm", sv, p) * inv
            q = np.cross(sv, e1[None])
            v = np.einsum("rmk,rmk->rm", np.broadcast_to(d, q.shape), q) * inv
            t = np.einsum("rmk,mk->rm", q, e2) * inv
            ok = ((det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1)
                  & (t >= r[:, 6:7]) & (t <= r[:, 7:8]))
        tt = np.where(ok, t, np.inf)
        j = np.argmin(tt, axis=1)
        hit = np.isfinite(tt[np.arange(len(r)), j])
        rows = np.arange(len(r))
        blk = out[s:s + step]
        blk["prim"] = np.where(hit, j, MISS)
        if any_hit:
            blk["t"] = blk["u"] = blk["v"] = np.nan
            blk["prim"] = np.where(hit, 0, MISS)
        else:
            blk["t"] = np.where(hit, t[rows, j], np.nan)
            blk["u"] = np.where(hit, u[rows, j], np.nan)
            blk["v"] = np.where(hit, v[rows, j], np.nan)
    return out


def trace(a):
    name = {"auto": "bvh8"}.get(a.width, f"bvh{a.width}")
    tris = np.fromfile(os.path.join(a.dir, "triangles.f32"), "<f4").reshape(-1, 9).astype(np.float64)
    res = {"tracer": name, "threads": a.threads, "triangles": len(tris), "build_ms": 0.0,
           "fake": True, "sets": {}}
    for s in ("primary", "diffuse", "shadow"):
        rays = np.fromfile(os.path.join(a.dir, f"{s}.rays"), "<f4").reshape(-1, 8).astype(np.float64)
        t0 = time.perf_counter()
        out = brute(tris, rays, s == "shadow")
        dt = max(time.perf_counter() - t0, 1e-9)
        k = int(os.environ.get("FAKE_SPT_CORRUPT", "0"))
        if s == "primary" and k:
            for i in range(min(k, len(out))):
                p = int(out["prim"][i])
                if i % 2 == 0:
                    out["prim"][i] = MISS
                    out["t"][i] = out["u"][i] = out["v"][i] = np.nan
                else:
                    out["prim"][i] = (p + 1) % len(tris) if p != MISS else 0
        out.tofile(os.path.join(a.dir, f"{s}.{name}.hits"))
        res["sets"][s] = {"rays": len(rays), "mrays_per_s": len(rays) / dt / 1e6,
                          "hits": int((out["prim"] != MISS).sum())}
    print("fake_spt: brute force done", file=sys.stderr)
    print(json.dumps(res))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("group", choices=["rays"])
    sub = ap.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("export")
    e.add_argument("scene")
    e.add_argument("--out", required=True)
    e.add_argument("--width", type=int, default=1024)
    e.add_argument("--height", type=int, default=1024)
    e.add_argument("--eye"); e.add_argument("--center")
    e.add_argument("--subdivide", type=int, default=0)
    e.add_argument("--seed", type=int, default=1)
    t = sub.add_parser("trace")
    t.add_argument("dir")
    t.add_argument("--threads", type=int, default=1)
    t.add_argument("--passes", type=int, default=5)
    t.add_argument("--bvh-width", dest="width", default="auto", choices=["4", "8", "auto"])
    a = ap.parse_args()
    export(a) if a.cmd == "export" else trace(a)


if __name__ == "__main__":
    main()
