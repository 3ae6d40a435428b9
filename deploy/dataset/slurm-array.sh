#!/usr/bin/env bash
# A dataset rendered by a Slurm job array on shared storage: task I renders the samples whose
# index mod N equals I (N = the array's size; --resume skips samples an earlier attempt
# finished). Submit it, then the merge once every task succeeded:
#   jid=$(sbatch --parsable deploy/dataset/slurm-array.sh SPEC.toml /shared/out)
#   sbatch --dependency=afterok:$jid --wrap "nephele dataset SPEC.toml -o /shared/out --merge"
#SBATCH --job-name=nephele-dataset
#SBATCH --array=0-7
#SBATCH --cpus-per-task=2
#SBATCH --mem=4G
#SBATCH --time=12:00:00
set -euo pipefail
spec=${1:?usage: slurm-array.sh SPEC.toml OUTPUT_DIR}
out=${2:?usage: slurm-array.sh SPEC.toml OUTPUT_DIR}
# SLURM_ARRAY_TASK_COUNT is the array's size; nephele reads SLURM_ARRAY_TASK_ID (less
# SLURM_ARRAY_TASK_MIN) itself.
exec nephele dataset "$spec" -o "$out" --shards "${SLURM_ARRAY_TASK_COUNT}" --resume
