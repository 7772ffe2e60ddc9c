#!/usr/bin/env bash
# Writes the job list of a batch for GNU parallel (or any runner that takes
# one shell command per line): line N runs the main job on the N-th scan of
# the inputs (`csgvox batch INPUT... --task N`), its outputs in the same
# place as one `csgvox batch` would put them, its summary row in
# OUTDIR/rows/N/. A task run again skips a finished scan.
#
# Usage: joblist.sh OUTDIR INPUT... [-- MAIN-JOB OPTIONS] > jobs.txt
#   then: parallel --jobs 2 < jobs.txt                          (one machine)
#         parallel --sshloginfile nodes --jobs 1 < jobs.txt     (several; shared folders)
#         scripts/cluster/merge.sh OUTDIR "$(wc -l < jobs.txt)"
# The inputs must not change until every task has run. Set CSGVOX to the
# csgvox executable (default: csgvox on the PATH).
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

tasks=$("$csgvox" batch --list -o "$out" "${inputs[@]}" | wc -l)
common="$(printf '%q' "$csgvox") batch"
for i in "${inputs[@]}"; do common+=" $(printf '%q' "$i")"; done
common+=" -o $(printf '%q' "$out") --jobs 1 --resume --quiet"
for o in "${options[@]+"${options[@]}"}"; do common+=" $(printf '%q' "$o")"; done
for ((n = 1; n <= tasks; n++)); do
  echo "$common --task $n --summary-dir $(printf '%q' "$out/rows/$n")"
done
