#!/usr/bin/env python3
"""Ray-tracing throughput of our BVHs against Intel Embree 4 on identical ray sets.

`spt rays export` writes a ray set (triangle soup + three sets of rays) for a scene; each
tracer traces it and reports Mrays/s and BVH build time; this script alternates the
tracers over rounds, keeps medians, prints markdown tables (throughput, build time) and
checks the tracers' answers against each other, deciding disagreements with a float64
recomputation of the claimed intersections.

Tracers
  embree   bench/embree/embree_trace.c (compiled here into bench/embree/build/ when the
           binary is missing or older than the source), Embree 4 from the pip wheel
           `embreex` (dlopen of embreex.libs/libembree4-*.so.4), rtcIntersect1 /
           rtcOccluded1 per ray, default build quality. See bench/embree/README.md.
  ours     `spt rays trace DIR --threads T --passes P --bvh-width W` for each A in --ours
           (bvh4 → W = 4, bvh8 → 8, auto → auto); A@PATH runs the spt binary at PATH
           instead (labelled by its directory), e.g. a build of the commit before a change:
           --ours bvh8,bvh8@/tmp/before/target/release/spt
Both take chunks of 1024 rays from an atomic counter with T threads, trace every set P
times and report the fastest pass.

Usage (from the repository root, on an otherwise idle machine)
  python3 bench/embree_rays.py [--scenes bunny,sponza,bunny-sub2] [--threads 1,2]
        [--rounds 3] [--passes 5] [--spt target/release/spt] [--ours auto | bvh4,bvh8]
        (an --ours entry may be ACCEL:ARGS@SPT, e.g. "bvh8:--presplit 0.3", or
        "embree:--quality high" for Embree's spatial-split build as one more column,
        "embree:--packet 16" for Embree called with packets of 16 rays)
        [--width 1024 --height 1024] [--seed 1] [--json out.json]
        [--raysets NAME=DIR ...] [--reuse-rays] [--no-compare] [--eps 1e-6]
        [--embree-args '--build-threads 0']
  --scenes    names from the default list below, or NAME=PATH.obj for another OBJ file
  --raysets   trace existing ray-set directories instead of exporting (no spt needed
              for embree-only runs: --ours none)
Default scenes (paths relative to --shared, default ../shared; skipped when absent):
  bunny       scenes/bunny/bunny.obj
  sponza      scenes/sponza/sponza.obj  --eye -12,3,0 --center 10,5,0  (from inside)
  bunny-sub2  scenes/bunny/bunny.obj    --subdivide 2  (~1.1M triangles)
Ray sets are exported to bench/embree/build/rays/<scene>/ (gitignored; about 100 MB of
rays per scene at 1024x1024 plus 48 MB of hits per tracer).

Ray-set format (directory DIR, all little endian, no headers)
  triangles.f32       f32 x 9 per triangle: v0.xyz v1.xyz v2.xyz; count = size / 36
  primary.rays        f32 x 8 per ray: ox oy oz dx dy dz tmin tmax       closest hit
  diffuse.rays        same                                               closest hit
  shadow.rays         same; segments (d not normalised, tmax ~ 1-1e-4)   occlusion
  <set>.<tracer>.hits 16 bytes per ray: u32 prim (0xFFFFFFFF = miss), f32 t, f32 u, f32 v
                      (ours renamed <set>.<tracer>.<label>.hits after each run, so that
                      two spt binaries with the same accelerator keep their own; files of
                      earlier runs stay until removed, and files older than the run are
                      never read)
                      with hit = (1-u-v) v0 + u v1 + v v2 at o + t d. Shadow set: prim 0 =
                      occluded, 0xFFFFFFFF = free; t, u, v NaN. (embree also writes NaN
                      t/u/v for misses; their values are not read for misses.)
  Each tracer prints one JSON line on stdout:
  {"tracer": "embree"|"bvh4"|"bvh8", "threads": T, "triangles": n, "nodes": k (ours: wide nodes), "build_ms": x,
   "sets": {"primary": {"rays": n, "mrays_per_s": y, "hits": k}, "diffuse": ..., "shadow": ...}}
  (ours also "references": leaf entries, more than n with --presplit; with --count each set
  also has "nodes_per_ray" and "triangles_per_ray")

Hit checks (hits files of the last run of each tracer, per scene)
  primary/diffuse: agreement on hit/miss and prim. Each claimed hit is recomputed in float64
  (Moller-Trumbore on the claimed triangle) and classed valid / edge / invalid: edge when
  a barycentric is within EPS (--eps, default 1e-6) of its bound or t within EPS
  (relative) of tmin/tmax; the "invalid claims" column counts claims outside that.
  Disagreement hit vs miss: a valid hit -> the hitter is right, an invalid one -> the
  misser, edge -> tie. Two different prims: an invalid claim loses to a non-invalid one
  (neither if both invalid); otherwise the closer float64 t is right if it is valid, a tie
  if the two t agree within EPS relative or the closer one is an edge hit.
  t precision: |t - t64| / t64 over every hit (median, 99th percentile, max, and how many
  exceed 1e-6, issue 11's bound).
  shadow: agreement on occluded/free and the two kinds of disagreement (not adjudicated:
  that would need a brute-force search).
"""
import argparse, glob, importlib.util, json, os, platform, re, shlex, statistics, subprocess, sys, time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
EMB_DIR = os.path.join(HERE, "embree")
BUILD_DIR = os.path.join(EMB_DIR, "build")
SRC = os.path.join(EMB_DIR, "embree_trace.c")
BIN = os.path.join(BUILD_DIR, "embree_trace")
SETS = ("primary", "diffuse", "shadow")
MISS = 0xFFFFFFFF
HIT_DTYPE = np.dtype([("prim", "<u4"), ("t", "<f4"), ("u", "<f4"), ("v", "<f4")])
EPS = 1e-6

DEFAULT_SCENES = {
    "bunny": ("scenes/bunny/bunny.obj", []),
    # "--eye=-12,3,0": a separate "-12,3,0" would look like an option to argument parsers
    "sponza": ("scenes/sponza/sponza.obj", ["--eye=-12,3,0", "--center=10,5,0"]),
    "bunny-sub2": ("scenes/bunny/bunny.obj", ["--subdivide", "2"]),
}


def log(msg):
    print(msg, file=sys.stderr, flush=True)


# --------------------------------------------------------------------------------------
# Embree library and the C tracer
# --------------------------------------------------------------------------------------
def find_embree_lib():
    dirs = []
    spec = importlib.util.find_spec("embreex")
    if spec and spec.submodule_search_locations:
        dirs += list(spec.submodule_search_locations)
    if not dirs:
        try:
            import embreex  # noqa: F401
            dirs.append(os.path.dirname(embreex.__file__))
        except ImportError:
            pass
    for d in dirs:
        for pat in ("../embreex.libs/libembree4*.so*", "libembree4*.so*", "../embreex.libs/*embree4*"):
            hits = sorted(glob.glob(os.path.join(d, pat)))
            if hits:
                return os.path.normpath(hits[0])
    return None


def ensure_binary(cc):
    if os.path.exists(BIN) and os.path.getmtime(BIN) >= os.path.getmtime(SRC):
        return BIN
    os.makedirs(BUILD_DIR, exist_ok=True)
    cmd = [cc, "-O2", "-std=c11", "-Wall", "-Wextra", "-pthread", "-o", BIN, SRC, "-ldl", "-lm"]
    log("compiling: " + shlex.join(cmd))
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"error: compiling {SRC} failed:\n{r.stderr}")
    if r.stderr.strip():
        log(r.stderr.rstrip())
    return BIN


# --------------------------------------------------------------------------------------
# Running tracers
# --------------------------------------------------------------------------------------
class TracerError(Exception):
    pass


def run_json(cmd, timeout):
    """Runs cmd, returns the last stdout line that parses as a JSON object with "sets"."""
    t0 = time.perf_counter()
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except FileNotFoundError as e:
        raise TracerError(f"cannot run {cmd[0]}: {e}")
    except subprocess.TimeoutExpired:
        raise TracerError(f"timed out after {timeout} s: {shlex.join(cmd)}")
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        tail = "\n".join((r.stderr or r.stdout).strip().splitlines()[-15:])
        raise TracerError(f"exit code {r.returncode}: {shlex.join(cmd)}\n{tail}")
    for line in reversed(r.stdout.splitlines()):
        line = line.strip()
        if line.startswith("{"):
            try:
                obj = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(obj, dict) and isinstance(obj.get("sets"), dict):
                obj["_wall_s"] = round(wall, 3)
                return obj
    raise TracerError(f"no JSON result line on stdout of {shlex.join(cmd)}:\n{r.stdout[-2000:]}")


def tracer_configs(args, embree_lib, spt):
    cfgs = [{"label": "embree", "kind": "embree", "extra": []}]
    for a in args.ours:
        # ACCEL[:ARGS][@PATH]: ARGS are more `spt rays trace` arguments (e.g.
        # "bvh8:--presplit 0.3"); @PATH traces with another spt binary (e.g. the commit
        # before a change, for a before/after ratio measured in the same run).
        # "embree:ARGS" is Embree again with more embree_trace arguments (e.g.
        # "embree:--quality high"), a column against its default build; it writes no hits.
        spec, _, exe = a.partition("@")
        accel, _, extra = spec.partition(":")
        if accel == "embree":
            if not extra:
                sys.exit("embree_rays.py: Embree's default build always runs; 'embree:ARGS' adds "
                         "another Embree column (e.g. 'embree:--quality high')")
            cfgs.append({"label": f"embree {extra}".strip(), "kind": "embree",
                         "extra": shlex.split(extra) + ["--no-write"]})
            continue
        if not spt:
            continue
        label = f"ours-{spec}@{os.path.basename(os.path.dirname(exe)) or exe}" if exe else f"ours-{spec}"
        cfgs.append({"label": label, "kind": "ours", "accel": accel, "extra": shlex.split(extra),
                     "spt": exe or spt})
    # Labels name the tables' columns and the hits files: two binaries in folders of the
    # same name would share them.
    slugs = [re.sub(r"[^A-Za-z0-9]+", "-", c["label"]).strip("-") for c in cfgs]
    if len(set(slugs)) != len(slugs):
        sys.exit("embree_rays.py: two --ours entries get the same label " +
                 f"({', '.join(c['label'] for c in cfgs)}): put the binaries in folders of different names")
    return cfgs


def tracer_cmd(cfg, d, threads, args, embree_bin, embree_lib, spt):
    if cfg["kind"] == "embree":
        return [embree_bin, d, "--lib", embree_lib, "--threads", str(threads),
                "--passes", str(args.passes)] + shlex.split(args.embree_args) + cfg["extra"]
    width = {"bvh4": "4", "bvh8": "8"}.get(cfg["accel"], cfg["accel"])
    return [cfg.get("spt", spt), "rays", "trace", d, "--threads", str(threads), "--passes", str(args.passes),
            "--bvh-width", width] + cfg["extra"]


# --------------------------------------------------------------------------------------
# Ray sets
# --------------------------------------------------------------------------------------
def count_records(path, size):
    n = os.path.getsize(path)
    if n % size:
        raise ValueError(f"{path}: size {n} is not a multiple of {size}")
    return n // size


def check_rayset(d):
    missing = [f for f in ["triangles.f32"] + [f"{s}.rays" for s in SETS]
               if not os.path.exists(os.path.join(d, f))]
    if missing:
        raise ValueError(f"{d}: missing {', '.join(missing)}")
    info = {"triangles": count_records(os.path.join(d, "triangles.f32"), 36)}
    for s in SETS:
        info[s] = count_records(os.path.join(d, f"{s}.rays"), 32)
    return info


def export_scene(spt, name, obj, extra, args, timeout):
    out = os.path.join(args.workdir, name)
    if args.reuse_rays:
        try:
            check_rayset(out)
            log(f"[{name}] reusing {out}")
            return out
        except (ValueError, OSError):
            pass
    os.makedirs(out, exist_ok=True)
    cmd = [spt, "rays", "export", obj, "--out", out, "--width", str(args.width),
           "--height", str(args.height), "--seed", str(args.seed)] + extra
    log(f"[{name}] export: {shlex.join(cmd)}")
    t0 = time.perf_counter()
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except (OSError, subprocess.TimeoutExpired) as e:
        raise TracerError(f"export failed: {e}")
    if r.returncode != 0:
        tail = "\n".join((r.stderr or r.stdout).strip().splitlines()[-15:])
        raise TracerError(f"export exit code {r.returncode}:\n{tail}")
    log(f"[{name}] exported in {time.perf_counter() - t0:.1f} s")
    return out


# --------------------------------------------------------------------------------------
# Hit checks
# --------------------------------------------------------------------------------------
def load_hits(path, n, since=0.0):
    if not os.path.exists(path):
        raise ValueError(f"missing {path}")
    if os.path.getmtime(path) < since:
        raise ValueError(f"{path} is older than this run (stale)")
    if os.path.getsize(path) != n * HIT_DTYPE.itemsize:
        raise ValueError(f"{path}: {os.path.getsize(path)} bytes, expected {n} x 16")
    return np.fromfile(path, HIT_DTYPE)


def intersect64(rays, tris, idx, prim):
    """float64 Moller-Trumbore of rays[idx] against tris[prim] (prim valid indices).
    Returns (t, state) with state 1 = valid, 0 = edge (within EPS), -1 = invalid."""
    r = rays[idx].astype(np.float64)
    tri = tris[prim].astype(np.float64)
    o, d, tmin, tmax = r[:, 0:3], r[:, 3:6], r[:, 6], r[:, 7]
    v0, e1, e2 = tri[:, 0:3], tri[:, 3:6] - tri[:, 0:3], tri[:, 6:9] - tri[:, 0:3]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        inv = 1.0 / det
        s = o - v0
        u = np.einsum("ij,ij->i", s, p) * inv
        q = np.cross(s, e1)
        v = np.einsum("ij,ij->i", d, q) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        m = np.minimum(np.minimum(u, v), 1.0 - u - v)
        bary = np.where(m > EPS, 1, np.where(m >= -EPS, 0, -1))
        et = EPS * np.maximum(np.abs(t), 1e-30)
        inside = (t > tmin + et) & (t < tmax - et)
        outside = (t < tmin - et) | (t > tmax + et)
        trange = np.where(inside, 1, np.where(outside, -1, 0))
        state = np.minimum(bary, trange)
        state = np.where((det != 0) & np.isfinite(t) & np.isfinite(m), state, -1)
    return t, state


def t_error_stats(h, t64, sel):
    """Relative error of the tracer's f32 t against t64 over the selected hits."""
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.abs(h["t"][sel].astype(np.float64) - t64) / np.abs(t64)
    rel = rel[np.isfinite(rel)]
    if rel.size == 0:
        return {"n": 0, "median": None, "p99": None, "max": None, "above": 0}
    # "above": hits off by more than issue 11's bound of 1e-6 relative.
    return {"n": int(rel.size), "median": float(np.median(rel)),
            "p99": float(np.percentile(rel, 99)), "max": float(rel.max()),
            "above": int((rel > 1e-6).sum())}


def compare_closest(rays, tris, ours, emb):
    n = len(rays)
    ntri = len(tris)
    res = {"rays": n}
    claims = {}
    for who, h in (("ours", ours), ("embree", emb)):
        hit = h["prim"] != MISS
        bad = hit & (h["prim"] >= ntri)
        idx = np.nonzero(hit & ~bad)[0]
        t64, state = intersect64(rays, tris, idx, h["prim"][idx].astype(np.int64))
        full_t = np.full(n, np.nan)
        full_s = np.full(n, -2, np.int8)  # -2: no claim
        full_t[idx], full_s[idx] = t64, state
        full_s[bad] = -1
        claims[who] = (hit, full_t, full_s)
        res[f"{who}_hits"] = int(hit.sum())
        res[f"{who}_invalid_claims"] = int(((full_s == -1) & hit).sum())
        res[f"{who}_edge_claims"] = int((full_s == 0).sum())
        res[f"{who}_prim_out_of_range"] = int(bad.sum())
        res[f"{who}_t_rel_err"] = t_error_stats(h, t64, idx)
        ok = state >= 0  # the same over claims that are valid or on an edge in float64
        res[f"{who}_t_rel_err_valid"] = t_error_stats(h, t64[ok], idx[ok])
    ha, ta, sa = claims["ours"]
    hb, tb, sb = claims["embree"]
    agree = (ha == hb) & (~ha | (ours["prim"] == emb["prim"]))
    res["agree"] = int(agree.sum())
    res["agree_frac"] = float(agree.mean()) if n else 1.0
    dis = ~agree
    res["disagree"] = int(dis.sum())
    ours_right = np.zeros(n, bool)
    emb_right = np.zeros(n, bool)
    tie = np.zeros(n, bool)
    neither = np.zeros(n, bool)
    # hit vs miss
    for hitter, sh, misser_right, hitter_right in (
            (ha & ~hb, sa, emb_right, ours_right), (hb & ~ha, sb, ours_right, emb_right)):
        hitter_right |= hitter & (sh == 1)
        misser_right |= hitter & (sh == -1)
        tie |= hitter & (sh == 0)
    # two different prims
    both = dis & ha & hb
    inv_a, inv_b = both & (sa == -1), both & (sb == -1)
    neither |= inv_a & inv_b
    emb_right |= inv_a & ~inv_b
    ours_right |= inv_b & ~inv_a
    ok = both & ~inv_a & ~inv_b
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.abs(ta - tb) / np.maximum(np.abs(ta), np.abs(tb))
    close = ok & (rel <= EPS)
    tie |= close
    far = ok & ~close
    a_closer = far & (ta < tb)
    b_closer = far & (tb < ta)
    ours_right |= a_closer & (sa == 1)
    emb_right |= b_closer & (sb == 1)
    tie |= (a_closer & (sa == 0)) | (b_closer & (sb == 0))
    neither |= far & ~a_closer & ~b_closer  # NaN t
    res["hit_vs_miss"] = int((dis & (ha != hb)).sum())
    res["prim_vs_prim"] = int(both.sum())
    res["ours_right"] = int(ours_right.sum())
    res["embree_right"] = int(emb_right.sum())
    res["tie"] = int(tie.sum())
    res["neither"] = int(neither.sum())
    res["examples"] = [int(i) for i in np.nonzero(dis)[0][:8]]
    return res


def compare_shadow(ours, emb):
    a, b = ours["prim"] != MISS, emb["prim"] != MISS
    n = len(a)
    agree = a == b
    return {"rays": n, "ours_hits": int(a.sum()), "embree_hits": int(b.sum()),
            "agree": int(agree.sum()), "agree_frac": float(agree.mean()) if n else 1.0,
            "ours_occluded_embree_free": int((a & ~b).sum()),
            "ours_free_embree_occluded": int((~a & b).sum()),
            "examples": [int(i) for i in np.nonzero(~agree)[0][:8]]}


def compare_scene(d, ours_names, since=0.0):
    """ours_names: {label: tracer name used in the hits file names}; hits files last
    written before `since` (a time.time()) are stale and skipped."""
    tris = np.fromfile(os.path.join(d, "triangles.f32"), "<f4").reshape(-1, 9)
    out = {}
    for s in SETS:
        rays = np.fromfile(os.path.join(d, f"{s}.rays"), "<f4").reshape(-1, 8)
        try:
            emb = load_hits(os.path.join(d, f"{s}.embree.hits"), len(rays), since)
        except ValueError as e:
            log(f"  hits check skipped: {e}")
            continue
        for label, name in ours_names.items():
            try:
                ours = load_hits(os.path.join(d, f"{s}.{name}.hits"), len(rays), since)
            except ValueError as e:
                log(f"  hits check skipped for {label}: {e}")
                continue
            r = compare_shadow(ours, emb) if s == "shadow" else compare_closest(rays, tris, ours, emb)
            r["ours_file"] = f"{s}.{name}.hits"
            out.setdefault(label, {})[s] = r
    return out


# --------------------------------------------------------------------------------------
# Tables
# --------------------------------------------------------------------------------------
def fmt(x, spec=".2f"):
    return "–" if x is None else format(x, spec)


def fmt_e(x):
    return "–" if x is None else f"{x:.1e}"


def num(x, spec):
    return format(x, spec) if isinstance(x, (int, float)) else repr(x)


def median(xs):
    xs = [x for x in xs if isinstance(x, (int, float))]
    return statistics.median(xs) if xs else None


def summarise(runs, scenes, threads, labels):
    thr, bld = [], []
    for sc in scenes:
        for T in threads:
            sel = [r for r in runs if r["scene"] == sc and r["threads"] == T and r["result"]]
            b = {"scene": sc, "threads": T}
            for lab in labels:
                rs = [r["result"] for r in sel if r["label"] == lab]
                b[lab] = median([x.get("build_ms") for x in rs])
                if rs:
                    b["triangles"] = rs[0].get("triangles")
            bld.append(b)
            for s in SETS:
                row = {"scene": sc, "set": s, "threads": T}
                for lab in labels:
                    rs = [r["result"]["sets"].get(s) for r in sel if r["label"] == lab]
                    rs = [x for x in rs if isinstance(x, dict)]
                    row[lab] = median([x.get("mrays_per_s") for x in rs])
                    if rs:
                        row["rays"] = rs[0].get("rays")
                thr.append(row)
    return thr, bld


def print_tables(thr, bld, hits, labels, rounds):
    ours = [l for l in labels if l != "embree"]
    print(f"\n### Throughput (Mrays/s, median of {rounds} rounds; ratio > 1: ours faster)\n")
    head = ["scene", "set", "rays", "threads", "embree"] + sum(([l, f"{l} ÷ embree"] for l in ours), [])
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in thr:
        e = r.get("embree")
        cells = [r["scene"], r["set"], str(r.get("rays", "–")), str(r["threads"]), fmt(e)]
        for l in ours:
            o = r.get(l)
            cells += [fmt(o), fmt(o / e if o and e else None, ".3f")]
        print("| " + " | ".join(cells) + " |")
    print(f"\n### BVH build (ms, median of {rounds} rounds; ratio < 1: ours faster)\n")
    head = ["scene", "triangles", "threads", "embree"] + sum(([l, f"{l} ÷ embree"] for l in ours), [])
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in bld:
        e = r.get("embree")
        cells = [r["scene"], str(r.get("triangles", "–")), str(r["threads"]), fmt(e, ".1f")]
        for l in ours:
            o = r.get(l)
            cells += [fmt(o, ".1f"), fmt(o / e if o is not None and e else None, ".3f")]
        print("| " + " | ".join(cells) + " |")
    if not any(hits.values()):
        return
    print("\n### Closest hits: ours vs embree (float64 recomputation decides disagreements)\n")
    head = ["scene", "set", "ours", "agree %", "disagree", "hit/miss", "prim/prim", "ours right",
            "embree right", "tie", "neither", "invalid claims ours / embree",
            "t rel err embree med / p99 / max / hits > 1e-6",
            "t rel err ours med / p99 / max / hits > 1e-6"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for sc, per in hits.items():
        for lab, sets in per.items():
            for s in ("primary", "diffuse"):
                r = sets.get(s)
                if not r:
                    continue
                te, to = r["embree_t_rel_err"], r["ours_t_rel_err"]
                print("| " + " | ".join([
                    sc, s, lab, f"{100 * r['agree_frac']:.4f}", str(r["disagree"]),
                    str(r["hit_vs_miss"]), str(r["prim_vs_prim"]), str(r["ours_right"]),
                    str(r["embree_right"]), str(r["tie"]), str(r["neither"]),
                    f"{r['ours_invalid_claims']} / {r['embree_invalid_claims']}",
                    f"{fmt_e(te['median'])} / {fmt_e(te['p99'])} / {fmt_e(te['max'])} / {te['above']}",
                    f"{fmt_e(to['median'])} / {fmt_e(to['p99'])} / {fmt_e(to['max'])} / {to['above']}"])
                      + " |")
    print("\n### Shadow rays: ours vs embree\n")
    head = ["scene", "ours", "rays", "agree %", "occluded ours / embree",
            "ours occluded, embree free", "ours free, embree occluded"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for sc, per in hits.items():
        for lab, sets in per.items():
            r = sets.get("shadow")
            if r:
                print("| " + " | ".join([
                    sc, lab, str(r["rays"]), f"{100 * r['agree_frac']:.4f}",
                    f"{r['ours_hits']} / {r['embree_hits']}",
                    str(r["ours_occluded_embree_free"]), str(r["ours_free_embree_occluded"])]) + " |")


# --------------------------------------------------------------------------------------
def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def resolve_exe(p):
    if os.sep not in p:
        from shutil import which
        return which(p)
    for cand in (p, os.path.join(REPO, p)):
        if os.path.isfile(cand) and os.access(cand, os.X_OK):
            return os.path.abspath(cand)
    return None


def main():
    global EPS
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default=",".join(DEFAULT_SCENES),
                    help="comma list of default scene names or NAME=PATH.obj ('' for none)")
    ap.add_argument("--raysets", nargs="*", default=[], metavar="NAME=DIR",
                    help="existing ray-set directories to trace as well (no export)")
    ap.add_argument("--threads", default="1,2", help="comma list of thread counts")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--passes", type=int, default=5, help="passes per set inside each run")
    ap.add_argument("--spt", default="target/release/spt")
    ap.add_argument("--ours", default="auto",
                    help="comma list of our BVHs: bvh4, bvh8, auto (spt rays trace --bvh-width 4|8|auto), or 'none'")
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=1024)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--shared", default=os.path.normpath(os.path.join(REPO, "..", "shared")))
    ap.add_argument("--workdir", default=os.path.join(BUILD_DIR, "rays"),
                    help="where exported ray sets go (default bench/embree/build/rays)")
    ap.add_argument("--reuse-rays", action="store_true",
                    help="do not re-export a scene whose ray set already exists in --workdir")
    ap.add_argument("--embree-lib", help="libembree4.so.4 (default: from the embreex wheel)")
    ap.add_argument("--embree-args", default="",
                    help="extra embree_trace arguments, e.g. '--build-threads 0'")
    ap.add_argument("--cc", default="gcc")
    ap.add_argument("--eps", type=float, default=EPS,
                    help="tolerance of the hit checks (barycentric margin, relative t)")
    ap.add_argument("--no-compare", action="store_true", help="skip the hits checks")
    ap.add_argument("--timeout", type=float, default=1800, help="seconds per command")
    ap.add_argument("--json", help="write all results to this JSON file")
    args = ap.parse_args()
    EPS = args.eps
    args.ours = [] if args.ours.strip() in ("", "none") else [a.strip() for a in args.ours.split(",") if a.strip()]
    threads = [int(t) for t in args.threads.split(",") if t.strip()]
    if not threads or min(threads) < 1 or args.rounds < 1 or args.passes < 1:
        sys.exit("error: --threads, --rounds and --passes must be positive")

    embree_lib = args.embree_lib or find_embree_lib()
    if not embree_lib or not os.path.exists(embree_lib):
        sys.exit("error: Embree 4 library not found (pip install embreex, or --embree-lib PATH)")
    embree_bin = ensure_binary(args.cc)

    spt = resolve_exe(args.spt)
    if not spt:
        log(f"note: spt not found at {args.spt!r}: no export, and ours is skipped")

    # ---- scenes ----
    todo = []  # (name, obj or None, extra, dir or None)
    for item in [s.strip() for s in args.scenes.split(",") if s.strip()]:
        if "=" in item:
            name, path = item.split("=", 1)
            obj, extra = path, []
        elif item in DEFAULT_SCENES:
            name = item
            rel, extra = DEFAULT_SCENES[item]
            obj = os.path.join(args.shared, rel)
        else:
            sys.exit(f"error: unknown scene {item!r} (known: {', '.join(DEFAULT_SCENES)}; or NAME=PATH.obj)")
        if not os.path.exists(obj):
            log(f"[{name}] skipped: {obj} not found")
            continue
        if not spt:
            log(f"[{name}] skipped: exporting needs spt")
            continue
        todo.append((name, obj, extra, None))
    for item in args.raysets:
        if "=" not in item:
            sys.exit(f"error: --raysets wants NAME=DIR, got {item!r}")
        name, d = item.split("=", 1)
        todo.append((name, None, [], os.path.abspath(d)))
    if not todo:
        sys.exit("error: nothing to run (no scene found and no --raysets)")

    cfgs = tracer_configs(args, embree_lib, spt)
    labels = [c["label"] for c in cfgs]
    meta = {"date": time.strftime("%Y-%m-%d %H:%M:%S"), "cpu": cpu_model(),
            "nproc": os.cpu_count(), "embree_lib": embree_lib, "embree_bin": embree_bin,
            "spt": spt, "threads": threads, "rounds": args.rounds, "passes": args.passes,
            "width": args.width, "height": args.height, "seed": args.seed, "eps": EPS,
            "embree_args": args.embree_args,
            "configs": cfgs, "command": shlex.join(sys.argv)}
    runs, hits, scenes_done, raysets = [], {}, [], {}

    for name, obj, extra, d in todo:
        try:
            if d is None:
                d = export_scene(spt, name, obj, extra, args, args.timeout)
            info = check_rayset(d)
        except (TracerError, ValueError, OSError) as e:
            log(f"[{name}] skipped: {e}")
            continue
        raysets[name] = {"dir": d, "obj": obj, "export_args": extra, **info}
        log(f"[{name}] {info['triangles']} triangles, " +
            ", ".join(f"{info[s]} {s}" for s in SETS) + " rays")
        scenes_done.append(name)
        ours_names = {}
        started = time.time() - 1.0
        for rnd in range(args.rounds):
            for T in threads:
                for cfg in cfgs:
                    cmd = tracer_cmd(cfg, d, T, args, embree_bin, embree_lib, spt)
                    rec = {"scene": name, "round": rnd, "threads": T, "label": cfg["label"],
                           "cmd": shlex.join(cmd), "result": None}
                    try:
                        res = run_json(cmd, args.timeout)
                        rec["result"] = res
                        if cfg["kind"] == "ours":
                            # Each of our configurations keeps its own hits files (two
                            # binaries with the same accelerator write the same names).
                            tracer = str(res.get("tracer", cfg["accel"]))
                            slug = re.sub(r"[^A-Za-z0-9]+", "-", cfg["label"]).strip("-")
                            for s in SETS:
                                src = os.path.join(d, f"{s}.{tracer}.hits")
                                if os.path.exists(src):
                                    os.replace(src, os.path.join(d, f"{s}.{tracer}.{slug}.hits"))
                            ours_names[cfg["label"]] = f"{tracer}.{slug}"
                        msg = "  ".join(f"{s} {num(res['sets'][s].get('mrays_per_s'), '.2f')}"
                                        for s in SETS if isinstance(res["sets"].get(s), dict))
                        log(f"[{name}] round {rnd + 1}/{args.rounds} T={T} {cfg['label']}: "
                            f"build {num(res.get('build_ms'), '.1f')} ms  {msg} Mrays/s")
                    except TracerError as e:
                        rec["error"] = str(e)
                        log(f"[{name}] round {rnd + 1} T={T} {cfg['label']} FAILED: {e}")
                    runs.append(rec)
        if not args.no_compare:
            log(f"[{name}] checking hits ...")
            hits[name] = compare_scene(d, ours_names, started)

    thr, bld = summarise(runs, scenes_done, threads, labels)
    print(f"\nEmbree: {embree_lib}\nCPU: {meta['cpu']} ({meta['nproc']} logical CPUs); "
          f"{args.rounds} rounds x {args.passes} passes")
    print_tables(thr, bld, hits, labels, args.rounds)
    failed = [r for r in runs if not r["result"]]
    if failed:
        print(f"\n{len(failed)} run(s) failed; see stderr" + (" and the JSON" if args.json else ""))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"meta": meta, "raysets": raysets, "runs": runs, "throughput": thr,
                       "build": bld, "hits": hits}, f, indent=1)
        log(f"wrote {args.json}")


if __name__ == "__main__":
    main()
