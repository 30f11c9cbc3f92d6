#!/usr/bin/env bash
# Submits a sequence's denoise to Slurm (issue 19): a job array with one `mcrecon plan` chunk per
# task, then the check job once every task has ended.
#   MCRECON=/shared/bin/mcrecon FRAMES=1-240 CHUNK=24 WARMUP=8 \
#     farm/slurm/submit.sh [SBATCH OPTIONS] -- denoise IN_####.exr -o OUT_####.exr -f bmfr
# SBATCH OPTIONS (e.g. --partition=render --cpus-per-task=8) go to both jobs. Run it from the
# directory the jobs should work in (relative paths and the logs are taken from there).
# Prints: array job ID, check job ID.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
usage() { sed -n '2,8p' "$0" >&2; exit 2; }
: "${FRAMES:?set FRAMES, the frames of the sequence (e.g. 1-240)}"
: "${CHUNK:?set CHUNK, frames per array task}"
MCRECON=$(command -v "${MCRECON:-mcrecon}") || { echo "submit: no mcrecon CLI" >&2; exit 2; }
# The tasks run elsewhere, maybe in another directory: an absolute path.
MCRECON=$(realpath "$MCRECON")
WARMUP=${WARMUP:-0}
export MCRECON FRAMES CHUNK WARMUP

opts=()
while (($#)) && [ "$1" != -- ]; do opts+=("$1"); shift; done
(($#)) || usage
shift
(($#)) || usage

# The plan checks the arguments here, before anything is queued; its length sizes the array.
n=$("$MCRECON" plan --frames "$FRAMES" --chunk "$CHUNK" --warmup "$WARMUP" --json -- "$@" |
  python3 -c 'import json, sys; print(len(json.load(sys.stdin)))')

# --export=ALL: the tasks read MCRECON, FRAMES, CHUNK, WARMUP even where the site exports nothing.
array=$(sbatch --parsable --export=ALL --array="1-$n" "${opts[@]}" "$here/mcrecon_array.sh" "$@")
array=${array%%;*}
# afterany, not afterok: when a task fails for good the check still runs and names the frames
# missing, instead of waiting forever on a dependency that can no longer be met.
check=$(sbatch --parsable --export=ALL --dependency="afterany:$array" "${opts[@]}" \
  "$here/mcrecon_check.py" "$@")
check=${check%%;*}
echo "submit: array job $array ($n tasks of $CHUNK frames, warm-up $WARMUP), check job $check" >&2
echo "$array $check"
