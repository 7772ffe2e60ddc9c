#!/usr/bin/env bash
# Runs `csgvox compare` on every bundled scan (clean and noisy) and prints a
# Markdown table (scripts/compare-table.py): per method, wall time,
# primitives/operations, IoU against the part's true tree, Chamfer in % of D.
# Usage: scripts/compare-all.sh BINARY OUTDIR [compare options...]
set -euo pipefail
bin=$1 out=$2
shift 2
here=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
for scan in "$here"/data/*/scan.ply "$here"/data/*/scan_noisy.ply; do
  part=$(basename "$(dirname "$scan")")
  name=$part$([[ $scan == *noisy* ]] && echo "-noisy" || true)
  "$bin" compare "$scan" -q -o "$out/$name" "$@" > "$out/$name.log" 2>&1 || echo "$name: failed" >&2
done
"$here/scripts/compare-table.py" "$bin" "$out"
