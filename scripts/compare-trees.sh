#!/usr/bin/env bash
# Runs the main job on every bundled scan and writes or compares its trees.
#   scripts/compare-trees.sh CSGVOX REFDIR            write REFDIR/<part>-<scan>.json
#   scripts/compare-trees.sh CSGVOX REFDIR --check    compare with REFDIR, byte for byte
# Extra arguments after --check (or after REFDIR) are passed to csgvox.
# Exit 0 when every tree was written or is identical; 1 otherwise.
set -uo pipefail
bin=$1; ref=$2; shift 2
check=0
if [[ ${1:-} == --check ]]; then check=1; shift; fi
data="$(cd "$(dirname "$0")/../data" && pwd)"
mkdir -p "$ref"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
status=0
for scan in "$data"/*/scan.ply "$data"/*/scan_noisy.ply; do
  part=$(basename "$(dirname "$scan")"); name="$part-$(basename "$scan" .ply)"
  if ! "$bin" "$scan" -o "$work/$name" -q "$@" 2>"$work/$name.err"; then
    echo "FAILED $name: $(cat "$work/$name.err")"; status=1; continue
  fi
  if ((check)); then
    if cmp -s "$ref/$name.json" "$work/$name/tree.json"; then echo "same    $name"
    else echo "CHANGED $name"; status=1; fi
  else
    cp "$work/$name/tree.json" "$ref/$name.json"; echo "wrote   $name"
  fi
done
exit $status
