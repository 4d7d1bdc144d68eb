#!/bin/sh
# Renders one shard of a render, taking the shard's index from whichever scheduler
# started it, and writes OUT_DIR/shard-K-of-N.partial; then `spt merge` joins them.
#
#   SHARDS        number of shards N (required)
#   SHARD_INDEX   1-based index K, if set; else
#   JOB_COMPLETION_INDEX   (Kubernetes Indexed Job, 0-based) + 1; else
#   SLURM_ARRAY_TASK_ID    (Slurm job array, started as --array=1-N)
#   OUT_DIR       where the partial goes (default: .)
#   SPT           the spt binary (default: spt on PATH)
#   CHECKPOINT    seconds between checkpoints (default 60): a rerun of a killed shard
#                 resumes from its last checkpoint and writes the same bytes.
#
# Every other argument goes to `spt render` unchanged: the scene and every setting, the
# same on every shard (seed included: the default seed is 0 everywhere).
#
#   SHARDS=8 SHARD_INDEX=3 OUT_DIR=parts deploy/shard-entry.sh scene.obj --spp 4096
set -eu

: "${SHARDS:?set SHARDS to the number of shards}"
if [ -n "${SHARD_INDEX:-}" ]; then
    index=$SHARD_INDEX
elif [ -n "${JOB_COMPLETION_INDEX:-}" ]; then
    index=$((JOB_COMPLETION_INDEX + 1))
elif [ -n "${SLURM_ARRAY_TASK_ID:-}" ]; then
    index=$SLURM_ARRAY_TASK_ID
else
    echo "shard-entry.sh: no shard index (set SHARD_INDEX, JOB_COMPLETION_INDEX or SLURM_ARRAY_TASK_ID)" >&2
    exit 2
fi
out_dir=${OUT_DIR:-.}
mkdir -p "$out_dir"
exec "${SPT:-spt}" render "$@" \
    --shard "$index/$SHARDS" \
    --write-partial "${CHECKPOINT:-60}" \
    -o "$out_dir/shard-$index-of-$SHARDS.partial"
