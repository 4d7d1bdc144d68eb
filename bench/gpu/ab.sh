#!/usr/bin/env bash
# Two spt binaries against each other in one run, alternating, on the GPU's frame
# benchmark (as behind the "same run, alternating binaries" figures in docs/gpu.md):
# ROUNDS rounds of each scene with OLD then NEW, printing M samples/s per line.
#
#   bench/gpu/ab.sh OLD_SPT NEW_SPT [extra `spt bench` options…]
#
# Builds from 2026-11-30 on default to Russian roulette's scale 2, earlier ones had 1: pass
# `--rr-scale 1` (or 2) when both binaries know the option, else the two differ in it.
#   SCENES=../shared/scenes ROUNDS=2 W=1920 H=1080 SPP=16 FRAMES=10 bench/gpu/ab.sh …
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 OLD_SPT NEW_SPT [spt bench options…]" >&2; exit 2; }
old=$1 new=$2
shift 2
SCENES=${SCENES:-../shared/scenes}
ROUNDS=${ROUNDS:-2}
W=${W:-1920} H=${H:-1080} SPP=${SPP:-16} FRAMES=${FRAMES:-10}
scenes=(
    "cornell-box/CornellBox-Original.obj"
    "sponza/sponza.obj --eye=-12,3,0 --center=10,5,0"
    "bunny/bunny.obj"
)
for round in $(seq "$ROUNDS"); do
    for bin in "$old" "$new"; do
        for entry in "${scenes[@]}"; do
            read -r -a words <<<"$entry"
            "$bin" bench "$SCENES/${words[0]}" "${words[@]:1}" --backend gpu --width "$W" --height "$H" \
                --max-depth 5 --modes hero --sampler independent --spp "$SPP" --frames "$FRAMES" "$@" 2>/dev/null |
                awk -v r="$round" -v b="$bin" -v s="${words[0]}" '/^hero/ {print r, b, s, $4 " M samples/s"}'
        done
    done
done
