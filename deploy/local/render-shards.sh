#!/bin/sh
# Renders a scene as N shard processes on this machine (or, with GNU parallel's
# --sshloginfile, on a few machines) and merges them.
#
#   deploy/local/render-shards.sh N OUT.exr SCENE [spt render options...]
#
#   SPT       the spt binary (default: spt on PATH)
#   JOBS      shards run at once (default: N)
#   THREADS   threads per shard (default: 0 = one per core; use cores / JOBS)
#   PARTS     directory for the partials (default: OUT.exr.parts)
#
# Uses GNU parallel when it is installed, else xargs -P. The image equals
# `spt render SCENE [options] -o OUT.exr` byte for byte.
set -eu

if [ $# -lt 3 ]; then
    echo "usage: $0 N OUT.exr SCENE [spt render options...]" >&2
    exit 2
fi
shards=$1
out=$2
shift 2
here=$(cd "$(dirname "$0")/.." && pwd)
parts=${PARTS:-$out.parts}
mkdir -p "$parts"
export SHARDS="$shards" OUT_DIR="$parts" SPT="${SPT:-spt}"

if command -v parallel >/dev/null 2>&1; then
    seq 1 "$shards" | parallel --halt now,fail=1 -j "${JOBS:-$shards}" \
        SHARD_INDEX={} "$here/shard-entry.sh" "$@" --threads "${THREADS:-0}"
else
    seq 1 "$shards" | xargs -P "${JOBS:-$shards}" -I{} \
        env SHARD_INDEX={} "$here/shard-entry.sh" "$@" --threads "${THREADS:-0}"
fi

# shellcheck disable=SC2046 # the partials' names have no spaces: shard-K-of-N.partial
"$SPT" merge $(seq 1 "$shards" | sed "s|.*|$parts/shard-&-of-$shards.partial|") -o "$out" --force
