#!/bin/bash
# Submits the surface array and the merge job that waits for it:
#   TOP=protein.pdb TRAJ=run.xtc FRAMES=0:5000:5 ./submit.sh
# Settings travel to both jobs through the environment (sbatch --export=ALL, the default).
set -euo pipefail
HERE=$(dirname "$0")
mkdir -p logs
JOBID=$(sbatch --parsable "$HERE/surfaces.sbatch")
JOBID=${JOBID%%;*}   # "jobid;cluster" on multi-cluster sites
sbatch --dependency=afterok:"$JOBID" "$HERE/merge.sbatch"
echo "array job $JOBID; the merge runs when all its tasks succeed"
