#!/usr/bin/env python3
"""Time to error: our path tracer against Mitsuba 3 on the shared Cornell box, in one run.

Each configuration renders the reference's view (256 x 256 by default) at S samples per
pixel; its error is the relMSE against the converged 4096-spp reference in
../shared/refs/cornell-box-original/ (spectral reference for spectral modes, RGB for
RGB); its time is the wall time of the sampling alone (Mitsuba: the timed `mi.render`
after a warm-up render that JIT-compiles the kernels; ours: the sampling time `spt
render` prints, after loading and BVH build). Configurations run alternately, R rounds
with a different seed each, so that machine noise hits them all alike.

    efficiency = 1 / (relMSE x time)

and the ratio of two efficiencies is the speed-up at equal error (for an unbiased
estimator relMSE ~ 1/spp, so relMSE x time does not depend on spp).

Usage (from the repository root, after `cargo build --release -p cli`):

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
    python3 bench/time_to_error.py [--res 256] [--spp 64] [--threads 2] [--rounds 3] \\
        [CONFIG ...]

CONFIG is `mitsuba:VARIANT:SAMPLER` (e.g. mitsuba:llvm_ad_spectral:multijitter) or
`ours[@SPT]:MODE:SAMPLER[:extra spt flags]` (e.g. ours:hero:zsobol; `@SPT` runs another
spt binary, e.g. the previous commit's, so that a change is measured against it in the
same run); the default set is Mitsuba's llvm_ad_spectral with its independent,
multijitter and ldsampler samplers and ours in hero mode with the independent and zsobol
samplers. Prints one JSON line per configuration and a table, with each efficiency as a
ratio to Mitsuba's best (to the first configuration when no Mitsuba one runs).

Measuring one change against the commit before it, e.g.:

    git worktree add /tmp/before HEAD~1 && cargo build --release -p cli --manifest-path /tmp/before/Cargo.toml
    python3 bench/time_to_error.py --rounds 4 ours@/tmp/before/target/release/spt:hero:zsobol ours:hero:zsobol
"""
import argparse, json, os, re, subprocess, sys, tempfile, time

from compare_error import read_exr, rel_mse

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, ".."))
SHARED = os.path.normpath(os.path.join(REPO, "..", "shared"))
DEFAULT_LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
DEFAULT_CONFIGS = [
    "mitsuba:llvm_ad_spectral:independent",
    "mitsuba:llvm_ad_spectral:multijitter",
    "mitsuba:llvm_ad_spectral:ldsampler",
    "ours:hero:independent",
    "ours:hero:zsobol",
]


class Mitsuba:
    """One Mitsuba configuration: the scene loaded once, kernels warmed up."""

    def __init__(self, variant, sampler, a):
        if not os.environ.get("DRJIT_LIBLLVM_PATH") and os.path.exists(DEFAULT_LLVM):
            os.environ["DRJIT_LIBLLVM_PATH"] = DEFAULT_LLVM
        sys.path.insert(0, os.path.join(HERE, "mitsuba"))
        sys.path.insert(0, os.path.join(SHARED, "tools"))
        sys.dont_write_bytecode = True
        import bench_cornell
        import mitsuba_obj_reference as tools
        import drjit as dr
        import mitsuba as mi
        mi.set_log_level(mi.LogLevel.Warn)
        if a.threads > 0:
            dr.set_thread_count(a.threads)
        self.mi, self.dr, self.variant = mi, dr, variant
        mi.set_variant(variant)
        box = os.path.join(SHARED, "scenes", "cornell-box")
        d = bench_cornell.build_scene_dict(mi, os.path.join(box, "CornellBox-Original-fixed.obj"),
                                           os.path.join(box, "CornellBox-Original.mtl"), a.res, a.res, tools)
        d["sensor"]["sampler"] = {"type": sampler, "sample_count": a.spp}
        self.scene = mi.load_dict(d)
        self.render(1, 1_000_003)  # JIT tracing and compilation, first-touch allocation

    def render(self, spp, seed):
        self.mi.set_variant(self.variant)
        img = self.mi.render(self.scene, spp=spp, seed=seed)
        self.dr.eval(img)
        self.dr.sync_thread()
        return img

    def run(self, spp, seed, out):
        import numpy as np
        t0 = time.perf_counter()
        img = self.render(spp, seed)
        wall = time.perf_counter() - t0
        return wall, np.array(img, dtype=np.float64)[..., :3]


class Ours:
    """One configuration of our `spt render`."""

    def __init__(self, spt, mode, sampler, extra, a):
        self.cmd = [spt, "render", os.path.join(SHARED, "scenes", "cornell-box", "CornellBox-Original-fixed.obj"),
                    "--width", str(a.res), "--height", str(a.res), "--eye", "0,1,3.9", "--center", "0,1,0",
                    "--fov", "39.3077", "--rr-depth", "5", "--spectral", mode, "--sampler", sampler,
                    "--threads", str(a.threads)] + extra

    def run(self, spp, seed, out):
        p = subprocess.run(self.cmd + ["--spp", str(spp), "--seed", str(seed), "-o", out],
                           capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"{' '.join(self.cmd)}: {p.stderr}")
        m = re.search(r"wrote .*?: ([0-9.]+) s,", p.stderr)
        return float(m.group(1)), read_exr(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("configs", nargs="*", default=DEFAULT_CONFIGS)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--spt", default=os.path.join(REPO, "target", "release", "spt"))
    a = ap.parse_args()
    refs = {}
    for kind in ("spectral", "rgb"):
        stem = f"cornell-box-original_{kind}_256_4096spp.exr"
        refs[kind] = read_exr(os.path.join(SHARED, "refs", "cornell-box-original", stem))
    if a.res != 256:
        sys.exit("the references are 256 x 256: use --res 256")

    runners = []
    for c in a.configs:
        parts = c.split(":")
        if parts[0] == "mitsuba":
            ref = "rgb" if parts[1].endswith("rgb") else "spectral"
            runners.append((c, Mitsuba(parts[1], parts[2], a), ref))
        elif parts[0] == "ours" or parts[0].startswith("ours@"):
            spt = parts[0][len("ours@"):] or a.spt
            extra = parts[3].split() if len(parts) > 3 else []
            ref = "rgb" if parts[1] == "rgb" else "spectral"
            runners.append((c, Ours(spt, parts[1], parts[2], extra, a), ref))
        else:
            sys.exit(f"unknown configuration {c}")

    results = {c: {"walls": [], "errors": []} for c, _, _ in runners}
    tmp = tempfile.mkdtemp(prefix="time_to_error_")
    for r in range(a.rounds):
        for c, runner, ref in runners:
            wall, img = runner.run(a.spp, 17 + r, os.path.join(tmp, "ours.exr"))
            results[c]["walls"].append(wall)
            results[c]["errors"].append(rel_mse(img, refs[ref]))

    rows = []
    for c, _, _ in runners:
        walls, errors = sorted(results[c]["walls"]), results[c]["errors"]
        wall = walls[len(walls) // 2]
        err = sum(errors) / len(errors)
        row = {"config": c, "res": a.res, "spp": a.spp, "threads": a.threads, "rounds": a.rounds,
               "wall_s": round(wall, 4), "msamples_per_s": round(a.res * a.res * a.spp / wall / 1e6, 3),
               "rel_mse": round(err, 6), "efficiency": round(1.0 / (err * wall), 2)}
        rows.append(row)
        print(json.dumps(row), flush=True)
    best = max((r for r in rows if r["config"].startswith("mitsuba")), key=lambda r: r["efficiency"], default=None)
    anchor = "Mitsuba's best" if best else "the first"
    best = best or rows[0]
    print(f"\n| configuration | M samples/s | relMSE at {a.spp} spp | efficiency | ÷ {anchor} |")
    print("|---|---:|---:|---:|---:|")
    for r in rows:
        ratio = r["efficiency"] / best["efficiency"]
        print(f"| {r['config']} | {r['msamples_per_s']:.2f} | {r['rel_mse']:.5f} | {r['efficiency']:.0f} | {ratio:.2f} |")


if __name__ == "__main__":
    main()
