#!/usr/bin/env bash
# Merges the summary rows the tasks of a job list or job array wrote into
# OUTDIR/rows/<n>/ into OUTDIR/summary.jsonl and OUTDIR/summary.csv (task
# order; the CSV header once). Tasks that wrote no row are listed on stderr
# and make the exit code 1.
#
# Usage: merge.sh OUTDIR [TASKS]   (TASKS: the number of tasks, to find missing ones)
set -euo pipefail
if [[ $# -lt 1 ]]; then
  echo "usage: $0 OUTDIR [TASKS]" >&2
  exit 2
fi
out=$1
tasks=${2:-}
rows="$out/rows"
[[ -d $rows ]] || { echo "$rows: no such folder" >&2; exit 1; }
mapfile -t dirs < <(find "$rows" -mindepth 1 -maxdepth 1 -type d -printf '%f\n' | sort -n)
jsonl="$out/summary.jsonl"
csv="$out/summary.csv"
tmp_jsonl="$jsonl.merging"
tmp_csv="$csv.merging"
: > "$tmp_jsonl"
: > "$tmp_csv"
missing=0
header_done=0
for d in "${dirs[@]}"; do
  if [[ ! -s $rows/$d/summary.jsonl ]]; then
    echo "task $d: no row" >&2
    missing=$((missing + 1))
    continue
  fi
  cat "$rows/$d/summary.jsonl" >> "$tmp_jsonl"
  if [[ $header_done -eq 0 ]]; then
    head -n 1 "$rows/$d/summary.csv" >> "$tmp_csv"
    header_done=1
  fi
  tail -n +2 "$rows/$d/summary.csv" >> "$tmp_csv"
done
if [[ -n $tasks ]]; then
  for ((i = 1; i <= tasks; i++)); do
    if [[ ! -d $rows/$i ]]; then
      echo "task $i: no row" >&2
      missing=$((missing + 1))
    fi
  done
fi
mv "$tmp_jsonl" "$jsonl"
mv "$tmp_csv" "$csv"
echo "merged $(wc -l < "$jsonl") rows into $jsonl and $csv" >&2
[[ $missing -eq 0 ]]
