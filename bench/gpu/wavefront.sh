#!/usr/bin/env bash
# The GPU path tracer's two designs against each other in one run, alternating (the
# "wavefront against the megakernel" figures in docs/gpu.md): the Cornell box, Sponza from
# inside and the bunny subdivided to 1.1M triangles at W×H, depth 5, hero wavelengths, the
# independent sampler; per round the megakernel, then the wavefront with the binary, 4-wide
# and 8-wide trees (16-spp viewer frames), then 1-spp frames of each design (the
# wavefront's also kept on the device); last, whether both give the same image bytes
# (Cornell box, 256², 16 spp, depth 5 and unbounded: the same on lavapipe, not on every GPU).
#
#   SPT=target/release/spt SCENES=../shared/scenes bench/gpu/wavefront.sh [OUTDIR]
set -euo pipefail
SPT=${SPT:-target/release/spt}
SCENES=${SCENES:-../shared/scenes}
OUT=${1:-/tmp/spt-gpu-wavefront}
ROUNDS=${ROUNDS:-2}
W=${W:-1920} H=${H:-1080}
mkdir -p "$OUT"
bunny2="$OUT/bunny-sub2.obj"
[ -f "$bunny2" ] || python3 "$(dirname "$0")/subdivide_obj.py" "$SCENES/bunny/bunny.obj" "$bunny2" 2
# Russian roulette's scale 1: the default when docs/gpu.md's figures were taken.
common=(--backend gpu --width "$W" --height "$H" --max-depth 5 --modes hero --sampler independent --rr-scale 1)
scenes=(
    "cornell $SCENES/cornell-box/CornellBox-Original.obj"
    "sponza $SCENES/sponza/sponza.obj --eye=-12,3,0 --center=10,5,0"
    "bunny-sub2 $bunny2"
)
row() { # LABEL SCENE-ARGS… -- BENCH-ARGS…: one line of M samples/s (and frames/s)
    local label=$1
    shift
    "$SPT" bench "$@" 2>/dev/null | awk -v l="$label" '/^hero/ {print l, $2 " frames/s", $4 " M samples/s"}'
}
{
    for round in $(seq "$ROUNDS"); do
        for entry in "${scenes[@]}"; do
            read -r -a words <<<"$entry"
            name=${words[0]} args=("${words[@]:1}")
            row "$round $name megakernel 16spp" "${args[@]}" "${common[@]}" --spp 16 --frames 6
            for width in 2 4 8; do
                row "$round $name wavefront-$width 16spp" "${args[@]}" "${common[@]}" --spp 16 --frames 6 \
                    --wavefront --bvh-width "$width"
            done
            row "$round $name megakernel 1spp" "${args[@]}" "${common[@]}" --spp 1 --frames 60
            row "$round $name wavefront 1spp" "${args[@]}" "${common[@]}" --spp 1 --frames 60 --wavefront
            row "$round $name wavefront 1spp-on-device" "${args[@]}" "${common[@]}" --spp 1 --frames 60 \
                --wavefront --frames-on-device
        done
    done
    for depth in 5 0; do
        for design in megakernel wavefront; do
            flag=()
            [ "$design" = wavefront ] && flag=(--wavefront)
            "$SPT" render "$SCENES/cornell-box/CornellBox-Original.obj" --backend gpu --width 256 --height 256 \
                --spp 16 --max-depth "$depth" "${flag[@]}" -o "$OUT/$design-$depth.exr" >/dev/null 2>&1
        done
        if cmp -s "$OUT/megakernel-$depth.exr" "$OUT/wavefront-$depth.exr"; then
            echo "depth $depth: the same image bytes"
        else
            echo "depth $depth: different image bytes"
        fi
    done
} | tee "$OUT/wavefront.txt"
