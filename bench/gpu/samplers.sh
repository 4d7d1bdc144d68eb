#!/usr/bin/env bash
# Error against time of the GPU's samplers (and the CPU's best) on the Cornell box, in one
# run: a GPU reference at 16384 spp with another seed, then `spt compare` with
# bench/gpu/samplers.json up to --spp-max. Writes OUTDIR/compare.{csv,png,svg}.
#
#   SPT=target/release/spt SCENES=../shared/scenes bench/gpu/samplers.sh OUTDIR
set -euo pipefail
SPT=${SPT:-target/release/spt}
SCENES=${SCENES:-../shared/scenes}
OUT=${1:-/tmp/spt-gpu-samplers}
SIZE=${SIZE:-256}
SPP_MAX=${SPP_MAX:-1024}
mkdir -p "$OUT"
scene="$SCENES/cornell-box/CornellBox-Original.obj"
# Russian roulette's scale 1: the default when docs/gpu.md's figures were taken.
common=(--width "$SIZE" --height "$SIZE" --rr-scale 1)
"$SPT" render "$scene" "${common[@]}" --backend gpu --spp 16384 --seed 987654 -o "$OUT/reference.exr"
"$SPT" compare "$scene" "${common[@]}" --configs "$(dirname "$0")/samplers.json" \
    --reference "$OUT/reference.exr" --spp-max "$SPP_MAX" -o "$OUT"
