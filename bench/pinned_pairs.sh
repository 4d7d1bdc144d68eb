#!/usr/bin/env bash
# Two spt binaries at the same time, each pinned to a core of its own (cores swapped every
# pair), so that both see the same machine state; prints each pair's samples/s and their
# ratio (B over A), then the median ratio. On shared 2-core machines runs one after the
# other spread ±10-15 %; concurrent pairs are steadier. Give `--threads 1` in the args.
#
#   bench/pinned_pairs.sh PAIRS A_SPT B_SPT render SCENE [spt render flags ...]
#
# e.g. bench/pinned_pairs.sh 10 /tmp/before/target/release/spt target/release/spt \
#        render ../shared/scenes/cornell-box/CornellBox-Original-fixed.obj --eye 0,1,3.9 \
#        --center 0,1,0 --fov 39.3077 --width 256 --height 256 --spp 64 --threads 1
set -euo pipefail
if [ $# -lt 4 ]; then sed -n 2,11p "$0"; exit 2; fi
pairs=$1 a=$2 b=$3; shift 3
command -v taskset >/dev/null || { echo "needs taskset (util-linux)" >&2; exit 2; }
[ "$(nproc)" -ge 2 ] || { echo "needs two cores" >&2; exit 2; }
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT
rate() { grep -o '[0-9.]* M samples/s' "$1" | cut -d' ' -f1; }
ratios=()
for i in $(seq "$pairs"); do
  if [ $((i % 2)) = 0 ]; then ca=0 cb=1; else ca=1 cb=0; fi
  taskset -c $ca "$a" "$@" -o "$dir/a.exr" 2>"$dir/a.log" &
  taskset -c $cb "$b" "$@" -o "$dir/b.exr" 2>"$dir/b.log"
  wait
  ra=$(rate "$dir/a.log") rb=$(rate "$dir/b.log")
  r=$(python3 -c "print(round($rb / $ra, 3))")
  ratios+=("$r")
  echo "pair $i: A $ra, B $rb M samples/s, B/A $r"
done
python3 -c "import statistics, sys; print('median B/A', statistics.median(map(float, sys.argv[1:])))" "${ratios[@]}"
