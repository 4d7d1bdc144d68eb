#!/bin/bash
# A Slurm job array: one task per shard. Submit with deploy/slurm/submit.sh, which
# also queues the merge after every task has succeeded:
#
#   SHARDS=16 deploy/slurm/submit.sh out.exr scene.obj --spp 4096
#
# Each task runs deploy/shard-entry.sh with SLURM_ARRAY_TASK_ID as its shard index
# (the array is 1..SHARDS). A task that fails or is preempted can be requeued as it
# is: it resumes from its checkpoint and writes the same bytes.
#SBATCH --job-name=spt-render
#SBATCH --cpus-per-task=8
#SBATCH --time=04:00:00
#SBATCH --requeue
#SBATCH --output=spt-render-%A_%a.log
set -euo pipefail

: "${SHARDS:?set SHARDS (submit.sh does)}"
: "${SPT_DEPLOY:?set SPT_DEPLOY to the deploy directory of the repository (submit.sh does)}"
export OUT_DIR="${OUT_DIR:-parts}"
exec "$SPT_DEPLOY/shard-entry.sh" "$@" --threads "${SLURM_CPUS_PER_TASK:-0}"
