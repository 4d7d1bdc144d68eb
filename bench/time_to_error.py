#!/usr/bin/env python3
"""Time to error: our path tracer against Mitsuba 3 on the shared Cornell box (or two scenes
built from it), in one run.

Each configuration renders the reference's view (256 x 256 by default) at S samples per
pixel; its error is the relMSE against a converged render: for the Cornell box the 4096-spp
reference in ../shared/refs/cornell-box-original/ (spectral reference for spectral modes,
RGB for RGB), for the other scenes each renderer's own (see --scene below); its time is the wall time of the sampling alone (Mitsuba: the timed `mi.render`
after a warm-up render that JIT-compiles the kernels; ours: the sampling time `spt
render` prints, after loading and BVH build). Configurations run alternately, R rounds
with a different seed each, each round starting one configuration later (the place in a
round matters by a few percent), so that machine noise hits them all alike.

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
samplers, and with zsobol and Mitsuba's rule for Russian roulette (`--rr-scale 1`; ours
keeps more paths by default). Prints one JSON line per configuration and a table, with
each efficiency as a ratio to Mitsuba's best (to the first configuration when no Mitsuba
one runs).

On the spheres, `"ours:hero:zsobol:--integrator path-caustics"` (light-traced caustics,
docs/figures.md) is the configuration that pays; on the diffuse boxes it is `path`.

--scene chooses the scene: `cornell` (the default; errors against the shared references),
`bunny-box` (the shared 69K-triangle bunny, flat-shaded white, standing in the box) or
`spheres-box` (a smooth-shaded glass sphere, index 1.5, and a silver mirror sphere in the
box: UV spheres of 16,128 triangles with vertex normals, written by this script). Issue 11
asks for the equal-error speed on these two as well. There are no shared references for
them: each renderer's error is measured against its own converged render (--ref-spp,
default 4096 spp, a multiple of 64, rendered once and kept in --workdir under a name
that hashes the scene's description; ours with zsobol, Mitsuba's with its independent
sampler in passes of 64 spp; delete them after a change that alters a renderer's image),
and the script prints how far the two references differ (their means per channel and their relMSE), which says whether the two
renderers draw the same image.

The vector width on both sides: `--simd avx2` in our flags, `--mitsuba-target znver3::8`
for Mitsuba (Dr.Jit's LLVM target for the whole run: CPU, features, lanes), e.g. on an
AVX-512 machine `--mitsuba-target znver3::8 mitsuba:llvm_ad_spectral:multijitter
"ours:hero:zsobol:--simd avx2"`.

Measuring one change against the commit before it, e.g.:

    git worktree add /tmp/before HEAD~1 && cargo build --release -p cli --manifest-path /tmp/before/Cargo.toml
    python3 bench/time_to_error.py --rounds 4 ours@/tmp/before/target/release/spt:hero:zsobol ours:hero:zsobol
"""
import argparse, json, os, sys, tempfile, time

from compare_error import read_exr, rel_mse, render_timed
from uv_sphere import write_uv_sphere

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
    "ours:hero:zsobol:--rr-scale 1",
]


CAMERA = ["--eye", "0,1,3.9", "--center", "0,1,0", "--fov", "39.3077"]
BOX = os.path.join(SHARED, "scenes", "cornell-box")
BOX_OBJ = os.path.join(BOX, "CornellBox-Original-fixed.obj")
BOX_MTL = os.path.join(BOX, "CornellBox-Original.mtl")
BUNNY_OBJ = os.path.join(SHARED, "scenes", "bunny", "bunny.obj")
# The bunny: scaled by 5, its feet on the floor, left of the short box.
BUNNY_SCALE, BUNNY_TRANSLATE = 5.0, (-0.45, -0.165, 0.45)
# The spheres: (name, centre, radius); the glass one on the floor in front of the tall box,
# the mirror on top of the short box.
SPHERES = [("glass", (-0.45, 0.3, 0.55), 0.3), ("mirror", (0.33, 0.85, 0.37), 0.25)]


class Scene:
    """A scene as both renderers load it: our `spt render` arguments, Mitsuba's scene
    dict, and the shared references if there are any."""

    def __init__(self, name, workdir):
        self.name = name
        self.dir = os.path.join(workdir, name)
        os.makedirs(self.dir, exist_ok=True)
        if name == "cornell":
            self.ours = [BOX_OBJ]
        elif name == "bunny-box":
            toml = os.path.join(self.dir, "scene.toml")
            with open(toml, "w") as f:
                f.write("[materials.bunny]\nmodel = \"lambert\"\nreflectance = 0.75\n\n")
                f.write(f"[[mesh]]\nfile = {json.dumps(BOX_OBJ)}\n\n")
                f.write(f"[[mesh]]\nfile = {json.dumps(BUNNY_OBJ)}\nmaterial = \"bunny\"\n"
                        f"scale = {BUNNY_SCALE}\ntranslate = {list(BUNNY_TRANSLATE)}\n")
            self.ours = [toml]
        elif name == "spheres-box":
            toml = os.path.join(self.dir, "scene.toml")
            with open(toml, "w") as f:
                f.write("[materials.glass]\nmodel = \"dielectric\"\nior = 1.5\n\n")
                f.write("[materials.mirror]\nmodel = \"conductor\"\nmetal = \"silver\"\n\n")
                f.write(f"[[mesh]]\nfile = {json.dumps(BOX_OBJ)}\n\n")
                for m, centre, radius in SPHERES:
                    obj = os.path.join(self.dir, f"{m}.obj")
                    with open(obj, "w") as o:
                        write_uv_sphere(o, centre, radius)
                    f.write(f"[[mesh]]\nfile = {json.dumps(obj)}\nmaterial = \"{m}\"\n\n")
            self.ours = [toml]
        else:
            sys.exit(f"unknown scene {name} (cornell, bunny-box, spheres-box)")
        # Names the references: the scene's description (our files; Mitsuba's dict is built
        # from the same constants).
        import hashlib
        h = hashlib.sha256(repr((BOX_OBJ, BUNNY_OBJ, BUNNY_SCALE, BUNNY_TRANSLATE, SPHERES)).encode())
        for f in self.ours:
            if f.endswith(".toml"):
                h.update(open(f, "rb").read())
        self.key = h.hexdigest()[:10]

    def shared_ref(self, kind):
        """The shared 4096-spp reference of `kind` (spectral, rgb), or None."""
        if self.name != "cornell":
            return None
        return os.path.join(SHARED, "refs", "cornell-box-original", f"cornell-box-original_{kind}_256_4096spp.exr")

    def mitsuba_dict(self, mi, res, tools):
        sys.path.insert(0, os.path.join(HERE, "mitsuba"))
        import bench_cornell
        d = bench_cornell.build_scene_dict(mi, BOX_OBJ, BOX_MTL, res, res, tools)
        if self.name == "bunny-box":
            t = mi.ScalarTransform4f().translate(list(BUNNY_TRANSLATE)).scale(BUNNY_SCALE)
            d["bunny"] = {"type": "obj", "filename": BUNNY_OBJ, "face_normals": True, "to_world": t,
                          "bsdf": {"type": "twosided", "bsdf": {
                              "type": "diffuse", "reflectance": {"type": "rgb", "value": [0.75] * 3}}}}
        elif self.name == "spheres-box":
            for m, _, _ in SPHERES:
                bsdf = ({"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0} if m == "glass"
                        else {"type": "conductor", "material": "Ag"})
                d[m] = {"type": "obj", "filename": os.path.join(self.dir, f"{m}.obj"), "bsdf": bsdf}
        return d


def set_llvm_target(dr, target):
    """--mitsuba-target CPU:FEATURES:WIDTH: Dr.Jit's `jit_llvm_set_target` (exported by
    libdrjit-core.so, called through ctypes), for every LLVM kernel compiled after it in
    this process, e.g. znver3::8 for AVX2 code eight lanes wide on an AVX-512 machine
    (Embree still picks its own kernels, but is called with packets of the new width)."""
    import ctypes
    cpu, features, width = target.split(":")
    core = ctypes.CDLL(os.path.join(os.path.dirname(dr.__file__), "libdrjit-core.so"))
    set_target = getattr(core, "_Z19jit_llvm_set_targetPKcS0_j")
    set_target.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
    set_target(cpu.encode(), features.encode(), int(width))
    get_width = getattr(core, "_Z21jit_llvm_vector_widthv")
    get_width.restype = ctypes.c_uint32
    if get_width() != int(width):
        sys.exit(f"--mitsuba-target {target}: Dr.Jit kept vector width {get_width()}")


class Mitsuba:
    """One Mitsuba configuration: the scene loaded once, kernels warmed up."""

    def __init__(self, variant, sampler, a, scene, spp=None):
        if not os.environ.get("DRJIT_LIBLLVM_PATH") and os.path.exists(DEFAULT_LLVM):
            os.environ["DRJIT_LIBLLVM_PATH"] = DEFAULT_LLVM
        sys.path.insert(0, os.path.join(SHARED, "tools"))
        sys.dont_write_bytecode = True
        import mitsuba_obj_reference as tools
        import drjit as dr
        import mitsuba as mi
        mi.set_log_level(mi.LogLevel.Warn)
        if a.threads > 0:
            dr.set_thread_count(a.threads)
        self.mi, self.dr, self.variant = mi, dr, variant
        mi.set_variant(variant)
        if a.mitsuba_target and variant.startswith("llvm"):
            set_llvm_target(dr, a.mitsuba_target)
        self.tools = tools
        d = scene.mitsuba_dict(mi, a.res, tools)
        d["sensor"]["sampler"] = {"type": sampler, "sample_count": spp or a.spp}
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

    def __init__(self, spt, mode, sampler, extra, a, scene):
        self.cmd = [spt, "render"] + scene.ours + CAMERA + [
                    "--width", str(a.res), "--height", str(a.res), "--rr-depth", "5", "--spectral", mode,
                    "--sampler", sampler, "--threads", str(a.threads)] + extra

    def run(self, spp, seed, out):
        return render_timed(self.cmd + ["--spp", str(spp), "--seed", str(seed), "-o", out], out)


def reference(scene, family, kind, a):
    """The converged image the errors of `family`'s (ours, mitsuba) configurations of
    `kind` (spectral, rgb) are measured against: the shared reference where there is one,
    else that renderer's own render at --ref-spp, rendered once into the scene's folder."""
    shared = scene.shared_ref(kind)
    if shared:
        return read_exr(shared)
    if a.ref_spp % 64:
        sys.exit(f"--ref-spp {a.ref_spp}: use a multiple of 64 (Mitsuba's reference renders in passes of 64)")
    path = os.path.join(scene.dir, f"reference_{family}_{kind}_{a.res}_{a.ref_spp}spp_{scene.key}.exr")
    if not os.path.exists(path):
        print(f"rendering {path} ...", flush=True)
        t0 = time.perf_counter()
        if family == "ours":
            mode = "rgb" if kind == "rgb" else "hero"
            Ours(a.spt, mode, "zsobol", [], a, scene).run(a.ref_spp, 4242, path)
        else:
            import numpy as np
            variant = "llvm_ad_rgb" if kind == "rgb" else "llvm_ad_spectral"
            passes = a.ref_spp // 64
            m = Mitsuba(variant, "independent", a, scene, spp=64)
            acc = sum(m.run(64, 4242 + k, None)[1] for k in range(passes)) / passes
            m.tools.write_exr(path, acc.astype(np.float32))
        print(f"  {time.perf_counter() - t0:.0f} s", flush=True)
    return read_exr(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("configs", nargs="*", default=DEFAULT_CONFIGS)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--mitsuba-target", metavar="CPU:FEATURES:WIDTH",
                    help="Dr.Jit's LLVM target for every Mitsuba configuration of the run, e.g. "
                         "znver3::8 (AVX2, 8 lanes) on an AVX-512 machine")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--spt", default=os.path.join(REPO, "target", "release", "spt"))
    ap.add_argument("--scene", default="cornell", help="cornell, bunny-box or spheres-box")
    ap.add_argument("--ref-spp", type=int, default=4096,
                    help="samples per pixel of each renderer's own reference (scenes without shared ones)")
    ap.add_argument("--workdir", default=os.path.join(HERE, "build", "time_to_error"),
                    help="where the generated scenes and references are kept (delete to re-render)")
    a = ap.parse_args()
    scene = Scene(a.scene, a.workdir)
    if scene.shared_ref("spectral") and a.res != 256:
        sys.exit("the references are 256 x 256: use --res 256")

    runners = []
    for c in a.configs:
        parts = c.split(":")
        if parts[0] == "mitsuba":
            kind = "rgb" if parts[1].endswith("rgb") else "spectral"
            runners.append((c, Mitsuba(parts[1], parts[2], a, scene), ("mitsuba", kind)))
        elif parts[0] == "ours" or parts[0].startswith("ours@"):
            spt = parts[0][len("ours@"):] or a.spt
            extra = parts[3].split() if len(parts) > 3 else []
            kind = "rgb" if parts[1] == "rgb" else "spectral"
            runners.append((c, Ours(spt, parts[1], parts[2], extra, a, scene), ("ours", kind)))
        else:
            sys.exit(f"unknown configuration {c}")
    refs = {key: reference(scene, *key, a) for key in sorted({key for _, _, key in runners})}
    kinds = {kind for _, kind in refs}
    for kind in sorted(kinds):
        if ("ours", kind) in refs and ("mitsuba", kind) in refs and not scene.shared_ref(kind):
            o, m = refs[("ours", kind)], refs[("mitsuba", kind)]
            print(f"{kind} references, ours / Mitsuba's: means {o.reshape(-1, 3).mean(0).round(4).tolist()} / "
                  f"{m.reshape(-1, 3).mean(0).round(4).tolist()}, relMSE between them {rel_mse(o, m):.5f}",
                  flush=True)

    results = {c: {"walls": [], "errors": []} for c, _, _ in runners}
    tmp = tempfile.mkdtemp(prefix="time_to_error_")
    for r in range(a.rounds):
        # Each round starts one configuration later: where a configuration runs in the
        # round changes its speed by a few percent on a shared machine (the one run second
        # after Mitsuba gained 3-5 % over the third, stop 41), so every place is taken
        # in turn (rounds a multiple of the configurations' count share them evenly).
        shift = r % len(runners)
        for c, runner, ref in runners[shift:] + runners[:shift]:
            wall, img = runner.run(a.spp, 17 + r, os.path.join(tmp, "ours.exr"))
            results[c]["walls"].append(wall)
            results[c]["errors"].append(rel_mse(img, refs[ref]))

    rows = []
    for c, _, _ in runners:
        walls, errors = sorted(results[c]["walls"]), results[c]["errors"]
        wall = walls[len(walls) // 2]
        err = sum(errors) / len(errors)
        row = {"config": c, "scene": a.scene, "res": a.res, "spp": a.spp, "threads": a.threads, "rounds": a.rounds,
               "wall_s": round(wall, 4), "msamples_per_s": round(a.res * a.res * a.spp / wall / 1e6, 3),
               "rel_mse": round(err, 6), "efficiency": round(1.0 / (err * wall), 2)}
        rows.append(row)
        print(json.dumps(row), flush=True)
    best = max((r for r in rows if r["config"].startswith("mitsuba")), key=lambda r: r["efficiency"], default=None)
    anchor = "Mitsuba's best" if best else "the first"
    best = best or rows[0]
    print(f"\nscene {a.scene}; errors against "
          + ("the shared references" if scene.shared_ref("spectral") else f"each renderer's own {a.ref_spp}-spp render"))
    print(f"\n| configuration | M samples/s | relMSE at {a.spp} spp | efficiency | ÷ {anchor} |")
    print("|---|---:|---:|---:|---:|")
    for r in rows:
        ratio = r["efficiency"] / best["efficiency"]
        print(f"| {r['config']} | {r['msamples_per_s']:.2f} | {r['rel_mse']:.5f} | {r['efficiency']:.0f} | {ratio:.2f} |")


if __name__ == "__main__":
    main()
