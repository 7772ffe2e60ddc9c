#!/usr/bin/env bash
# Writes the job list of a batch for GNU parallel (or any runner that takes
# one shell command per line): one line per scan, each running the main job
# on that scan alone and writing its summary row into OUTDIR/rows/<n>/.
#
# Usage: joblist.sh OUTDIR INPUT... [-- MAIN-JOB OPTIONS]
#   then: parallel --jobs 2 < jobs.txt                 (one machine)
#         parallel --sshloginfile nodes --jobs 1 < jobs.txt   (several)
#         scripts/cluster/merge.sh OUTDIR
# Set CSGVOX to the csgvox executable (default: csgvox on the PATH).
set -euo pipefail
if [[ $# -lt 2 ]]; then
  echo "usage: $0 OUTDIR INPUT... [-- MAIN-JOB OPTIONS]" >&2
  exit 2
fi
csgvox=${CSGVOX:-csgvox}
out=$1
shift
inputs=()
while [[ $# -gt 0 && $1 != "--" ]]; do
  inputs+=("$1")
  shift
done
[[ $# -gt 0 ]] && shift
options=("$@")

quote() { printf '%q' "$1"; }
n=0
"$csgvox" batch --list -o "$out" "${inputs[@]}" | while IFS= read -r scan; do
  n=$((n + 1))
  line="$(quote "$csgvox") batch $(quote "$scan") -o $(quote "$out")"
  line+=" --summary-dir $(quote "$out/rows/$n") --jobs 1 --resume --quiet"
  for o in "${options[@]+"${options[@]}"}"; do line+=" $(quote "$o")"; done
  echo "$line"
done
