#!/usr/bin/env python3
"""Render-throughput benchmark of Mitsuba 3 on the shared Cornell box, for comparison
with our path tracer.

Scene, camera, materials, light and integrator are exactly those of the shared reference
(../shared/refs/cornell-box-original/, built the same way as by
../shared/tools/mitsuba_obj_reference.py, whose OBJ/MTL helpers are imported from there):
pinhole camera eye (0,1,3.9) -> center (0,1,0), up (0,1,0), vertical fov 39.3077 deg; box
pixel filter; every `usemtl` group a two-sided Lambertian with albedo Kd; groups with Ke > 0
(the `light`) a one-sided area light of radiance Ke; integrator `path`, max_depth -1
(unbounded), rr_depth 5; independent sampler.

Per variant: load the scene (not timed), render once at 1 spp (warm-up: JIT tracing and
LLVM compilation for llvm_* variants, first-touch allocations; reported as warmup_s), then
time the real render W x H x S (wall_s, including the wait for the result to be computed).
Prints one JSON line per variant on stdout. See README.md.

Usage: python3 bench_cornell.py [--res 512 | --width W --height H] [--spp 64]
                                [--threads N] [--repeat R] [--out DIR] VARIANT [VARIANT ...]
"""
import argparse, json, os, resource, sys, time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
DEFAULT_SHARED = os.path.normpath(os.path.join(REPO, "..", "shared"))
DEFAULT_LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"  # Debian package libllvm19


def cpu_time():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def build_scene_dict(mi, obj, mtl, width, height, tools):
    """Scene dict identical to mitsuba_obj_reference.py (one mesh per usemtl group)."""
    import tempfile
    mats = tools.parse_mtl(mtl)
    files = tools.split_obj(obj, tempfile.mkdtemp(prefix="bench_cornell_"))
    d = {"type": "scene",
         "integrator": {"type": "path", "max_depth": -1, "rr_depth": 5},
         "sensor": {"type": "perspective", "fov": 39.3077, "fov_axis": "y",
                    "to_world": mi.ScalarTransform4f().look_at(
                        origin=[0.0, 1.0, 3.9], target=[0.0, 1.0, 0.0], up=[0.0, 1.0, 0.0]),
                    "sampler": {"type": "independent"},
                    "film": {"type": "hdrfilm", "width": width, "height": height,
                             "rfilter": {"type": "box"}, "pixel_format": "rgb"}}}
    for m, (fn, _ntri) in files.items():
        kd = mats.get(m, {}).get("Kd", [0.0, 0.0, 0.0])
        ke = mats.get(m, {}).get("Ke", [0.0, 0.0, 0.0])
        shape = {"type": "obj", "filename": fn, "face_normals": True,
                 "bsdf": {"type": "twosided", "bsdf": {
                     "type": "diffuse", "reflectance": {"type": "rgb", "value": kd}}}}
        if max(ke) > 0:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": ke}}
        d[m] = shape
    return d


def render_sync(mi, dr, scene, spp, seed):
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)        # JIT variants are lazy: force the kernels to run ...
    dr.sync_thread()    # ... and wait for them to finish
    return img


def bench_variant(mi, dr, variant, a, tools):
    mi.set_variant(variant)
    is_jit = variant.startswith(("llvm_", "cuda_"))
    t0 = time.perf_counter()
    scene = mi.load_dict(build_scene_dict(mi, a.obj, a.mtl, a.width, a.height, tools))
    load_s = time.perf_counter() - t0

    # Warm-up at 1 spp, same resolution: traces + compiles the kernels (LLVM variants),
    # fills Dr.Jit's kernel cache, touches the memory. Not part of wall_s.
    t0 = time.perf_counter()
    render_sync(mi, dr, scene, 1, seed=1_000_003)
    warmup_s = time.perf_counter() - t0

    walls, cpus, compiled, compile_ms = [], [], 0, 0.0
    img = None
    for r in range(a.repeat):
        if is_jit:
            dr.kernel_history()  # clear
            dr.set_flag(dr.JitFlag.KernelHistory, True)
        c0, t0 = cpu_time(), time.perf_counter()
        img = render_sync(mi, dr, scene, a.spp, seed=r)
        walls.append(time.perf_counter() - t0)
        cpus.append(cpu_time() - c0)
        if is_jit:
            dr.set_flag(dr.JitFlag.KernelHistory, False)
            for k in dr.kernel_history([dr.KernelType.JIT]):
                if not k.get("cache_hit", True):
                    compiled += 1
                    compile_ms += k.get("codegen_time", 0.0) + k.get("backend_time", 0.0)

    wall = min(walls)
    res = {"variant": variant, "width": a.width, "height": a.height, "spp": a.spp,
           "threads": dr.thread_count(), "wall_s": round(wall, 4),
           "samples_per_s": round(a.width * a.height * a.spp / wall, 1),
           "warmup_s": round(warmup_s, 4),
           # extras (see README): scene load time, all timed runs, process CPU time of
           # the fastest run (CPU/wall ~ effective parallelism), kernels compiled
           # during the timed renders (should be 0: compilation excluded)
           "load_s": round(load_s, 4),
           "wall_s_all": [round(w, 4) for w in walls],
           "cpu_s": round(cpus[walls.index(wall)], 4),
           "mitsuba": mi.__version__, "drjit": dr.__version__}
    if is_jit:
        res["jit_kernels_compiled_in_timed"] = compiled
        res["jit_compile_s_in_timed"] = round(compile_ms / 1000.0, 4)
    if a.out:
        import numpy as np
        os.makedirs(a.out, exist_ok=True)
        fn = os.path.join(a.out, f"cornell_{variant}_{a.width}x{a.height}_{a.spp}spp.exr")
        tools.write_exr(fn, np.array(img, dtype=np.float32))
        res["exr"] = fn
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("variants", nargs="+", help="e.g. scalar_spectral llvm_ad_spectral")
    ap.add_argument("--res", type=int, help="square resolution (sets width and height)")
    ap.add_argument("--width", type=int, default=512)
    ap.add_argument("--height", type=int, default=512)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--threads", type=int, default=0,
                    help="total render threads incl. the calling thread (= mitsuba -t N); "
                         "0 = Dr.Jit's default (one per logical CPU)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="timed renders per variant; wall_s is the fastest")
    ap.add_argument("--out", help="write the timed render as EXR into this directory")
    ap.add_argument("--shared", default=DEFAULT_SHARED,
                    help="shared data folder (default: ../shared from the repo root)")
    ap.add_argument("--obj", help="default: SHARED/scenes/cornell-box/CornellBox-Original-fixed.obj")
    ap.add_argument("--mtl", help="default: SHARED/scenes/cornell-box/CornellBox-Original.mtl")
    a = ap.parse_args()
    if a.res:
        a.width = a.height = a.res
    box = os.path.join(a.shared, "scenes", "cornell-box")
    a.obj = a.obj or os.path.join(box, "CornellBox-Original-fixed.obj")
    a.mtl = a.mtl or os.path.join(box, "CornellBox-Original.mtl")
    for p in (a.obj, a.mtl, os.path.join(a.shared, "tools", "mitsuba_obj_reference.py")):
        if not os.path.exists(p):
            sys.exit(f"missing {p} (shared data folder: --shared)")

    # Dr.Jit's LLVM backend loads libLLVM at run time; point it at Debian's libllvm19
    # unless the caller chose one. Must happen before drjit is imported.
    if not os.environ.get("DRJIT_LIBLLVM_PATH") and os.path.exists(DEFAULT_LLVM):
        os.environ["DRJIT_LIBLLVM_PATH"] = DEFAULT_LLVM

    sys.dont_write_bytecode = True  # no __pycache__ in ../shared/tools
    sys.path.insert(0, os.path.join(a.shared, "tools"))
    import mitsuba_obj_reference as tools  # parse_mtl, split_obj, write_exr
    import drjit as dr
    import mitsuba as mi
    mi.set_log_level(mi.LogLevel.Warn)

    avail = mi.variants()
    for v in a.variants:
        if v not in avail:
            sys.exit(f"variant {v} not available; available: {' '.join(avail)}")
    if a.threads > 0:
        # Same as `mitsuba -t N`: the nanothread pool shared by Mitsuba's scalar
        # renderer and Dr.Jit's LLVM backend gets N-1 workers + the calling thread.
        dr.set_thread_count(a.threads)

    for v in a.variants:
        print(json.dumps(bench_variant(mi, dr, v, a, tools)), flush=True)


if __name__ == "__main__":
    main()
