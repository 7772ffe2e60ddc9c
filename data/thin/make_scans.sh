#!/usr/bin/env bash
# Regenerates the scans of the thin-feature parts: data/thin/<part>/scan.ply
# (clean) and scan_noisy.ply (Gaussian noise, sigma = 0.5 % of the diagonal),
# 20 000 points each with normals (thin features need the points).
# Usage: data/thin/make_scans.sh [path/to/csgvox]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
csgvox=${1:-"$here/../../build/app/csgvox"}
seed=101
for tree in "$here"/*/tree.json; do
  part=$(dirname "$tree")
  "$csgvox" sample "$tree" -o "$part/scan.ply" --points 20000 --seed "$seed" --quiet
  "$csgvox" sample "$tree" -o "$part/scan_noisy.ply" --points 20000 --noise 0.005 \
    --seed $((seed + 1000)) --quiet
  seed=$((seed + 1))
done
