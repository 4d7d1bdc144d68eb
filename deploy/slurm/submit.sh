#!/bin/bash
# Queues a sharded render as a Slurm job array plus a merge that runs when every
# shard has succeeded.
#
#   SHARDS=16 deploy/slurm/submit.sh OUT.exr SCENE [spt render options...]
#
#   SHARDS   number of shards (array tasks 1..SHARDS)
#   OUT_DIR  where the partials go (default: OUT.exr.parts)
#   SPT      the spt binary on the compute nodes (default: spt on PATH)
set -euo pipefail

if [ $# -lt 2 ]; then
    echo "usage: SHARDS=N $0 OUT.exr SCENE [spt render options...]" >&2
    exit 2
fi
: "${SHARDS:?set SHARDS to the number of shards}"
out=$1
shift
deploy=$(cd "$(dirname "$0")/.." && pwd)
parts=${OUT_DIR:-$out.parts}
export SHARDS SPT_DEPLOY="$deploy" OUT_DIR="$parts"

array=$(sbatch --parsable --export=ALL --array="1-$SHARDS" "$deploy/slurm/render-array.sh" "$@")
partials=()
for k in $(seq 1 "$SHARDS"); do
    partials+=("$parts/shard-$k-of-$SHARDS.partial")
done
sbatch --parsable --dependency="afterok:$array" --job-name=spt-merge --output=spt-merge-%j.log \
    --wrap="${SPT:-spt} merge ${partials[*]} -o $out --stderr $out.stderr.exr --force"
echo "queued array $array ($SHARDS shards) and its merge into $out"
