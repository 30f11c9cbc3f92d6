#!/usr/bin/env bash
#SBATCH --job-name=mcrecon
#SBATCH --requeue
#SBATCH --open-mode=append
#SBATCH --output=mcrecon_%A_%a.log
# One chunk of `mcrecon plan` per Slurm array task (issue 19). submit.sh sizes the array and
# queues the check; by hand:
#   MCRECON=/shared/bin/mcrecon FRAMES=1-240 CHUNK=24 WARMUP=8 \
#     sbatch --array=1-10 mcrecon_array.sh denoise IN_####.exr -o OUT_####.exr -f bmfr
# Environment: MCRECON (the CLI, on a path every node sees; default: mcrecon on PATH), FRAMES
# (the whole sequence), CHUNK (frames per task), WARMUP (history frames before each chunk; bmfr: 8).
# Arguments: what follows `--` in `mcrecon plan`, i.e. denoise and its arguments.
# --requeue is safe: the plan's command carries --resume, so a requeued task keeps the frames that
# read completely and were made by the same filter, parameters and input, and redoes the rest.
set -euo pipefail
: "${SLURM_ARRAY_TASK_ID:?submit as an array job (sbatch --array=1-N, or submit.sh)}"
: "${FRAMES:?set FRAMES, the frames of the sequence (e.g. 1-240)}"
: "${CHUNK:?set CHUNK, frames per array task}"
MCRECON=$(command -v "${MCRECON:-mcrecon}") || { echo "mcrecon_array: no mcrecon CLI" >&2; exit 2; }

plan=$("$MCRECON" plan --frames "$FRAMES" --chunk "$CHUNK" --warmup "${WARMUP:-0}" \
  --task "$SLURM_ARRAY_TASK_ID" --exe "$MCRECON" --json -- "$@")
# The command is run from the plan's JSON argv, never through a shell: paths with spaces or quotes
# stay one argument and nothing in them is interpreted. exec: Slurm's signals reach mcrecon itself.
exec python3 -c '
import json, os, sys
chunks = json.loads(sys.argv[1])
if len(chunks) != 1:
    sys.exit("mcrecon_array: the plan gave %d chunks for one task" % len(chunks))
c = chunks[0]
print("mcrecon_array: task %d of job %s: frames %s, warm-up %d, restart %s"
      % (c["task"], os.environ.get("SLURM_ARRAY_JOB_ID", "?"), c["frames"], c["warmup"],
         os.environ.get("SLURM_RESTART_COUNT", "0")), file=sys.stderr, flush=True)
os.execv(c["argv"][0], c["argv"])
' "$plan"
