#!/usr/bin/env bash
# GPU against CPU figures in one run on one machine (issue 14): the Cornell box, Sponza
# from inside, the bunny subdivided to 1.1M triangles and three instanced bunnies, at 1920×1080, 1 spp, depth 5,
# hero mode. GPU: viewer frames (`spt bench --frames`: samples plus the display conversion,
# statistics kept on the device) of 1 and 16 spp, and whole renders of 1 and 16 spp (read-back
# and merge into the exact film included); CPU: frames and renders on all cores, renders on
# one core. Scene preparation (BVH build, kernel compile) is printed, not timed in.
#
#   SPT=target/release/spt SCENES=../shared/scenes bench/gpu/figures.sh [OUTDIR]
#
# Needs python3 (for the subdivided bunny, written once into OUTDIR).
set -euo pipefail
SPT=${SPT:-target/release/spt}
SCENES=${SCENES:-../shared/scenes}
OUT=${1:-/tmp/spt-gpu-figures}
W=${W:-1920} H=${H:-1080}
REPEATS=${REPEATS:-5}
FRAMES=${FRAMES:-100}
CPU_THREADS=${CPU_THREADS:-0}
# GPU BVH layouts to time: auto (the binary tree), 2 (binary), 4 and 8 (wide: GPU_WIDTHS="auto 4 8").
GPU_WIDTHS=${GPU_WIDTHS:-auto 2}
mkdir -p "$OUT"
here=$(dirname "$0")
bunny2="$OUT/bunny-sub2.obj"
[ -f "$bunny2" ] || python3 "$here/subdivide_obj.py" "$SCENES/bunny/bunny.obj" "$bunny2" 2

bench() { # NAME SCENE [ARGS...]: one scene on both backends
    local name=$1 scene=$2
    shift 2
    # The independent sampler on both backends (the viewer's; the Sobol samplers' cost and
    # gain are bench/gpu/samplers.sh's), and Russian roulette's scale 1, the default when
    # docs/gpu.md's figures were taken (it still plays at bounces 3 and 4 of depth 5).
    local common=(--width "$W" --height "$H" --max-depth 5 --modes hero --sampler independent --rr-scale 1 "$@")
    echo "## $name"
    for width in $GPU_WIDTHS; do
        local gpu=(--backend gpu --bvh-width "$width")
        # Viewer frames (statistics stay on the device; only display pixels come back).
        "$SPT" bench "$scene" "${common[@]}" "${gpu[@]}" --spp 1 --frames "$FRAMES"
        # The same frames drawn into a device buffer (the viewer's wgpu surface path), no read-back.
        "$SPT" bench "$scene" "${common[@]}" "${gpu[@]}" --spp 1 --frames "$FRAMES" --frames-on-device
        "$SPT" bench "$scene" "${common[@]}" "${gpu[@]}" --spp 16 --frames 10
        # Whole renders (read-back and merge into the exact film included).
        "$SPT" bench "$scene" "${common[@]}" "${gpu[@]}" --spp 1 --repeats "$REPEATS"
        "$SPT" bench "$scene" "${common[@]}" "${gpu[@]}" --spp 16 --repeats 3
    done
    "$SPT" bench "$scene" "${common[@]}" --backend cpu --spp 1 --frames 5 --threads "$CPU_THREADS"
    "$SPT" bench "$scene" "${common[@]}" --backend cpu --spp 1 --repeats 3 --threads "$CPU_THREADS"
    "$SPT" bench "$scene" "${common[@]}" --backend cpu --spp 1 --repeats 1 --threads 1
}

{
    echo "# $(date -u +%FT%TZ) $("$SPT" --version) on $(nproc) cores"
    command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader
    bench cornell "$SCENES/cornell-box/CornellBox-Original.obj"
    bench sponza-inside "$SCENES/sponza/sponza.obj" --eye=-12,3,0 --center=10,5,0
    bench bunny-sub2 "$bunny2"
    # Two-level traversal on the GPU: one 69K-triangle bunny placed three times (the
    # file names the shared bunny relative to itself).
    bench bunnies "$here/../../scenes/bunnies.toml"
} 2>&1 | tee "$OUT/figures.txt"
