#!/usr/bin/env bash
# Regenerates the bundled scans of every part: data/<part>/scan.ply (clean)
# and data/<part>/scan_noisy.ply (Gaussian noise, sigma = 0.5 % of the
# diagonal), 10 000 points each with normals, and data/<part>/scan_scanner.ply
# (the default turntable scanner model, docs/scanner.md: raw x y z, 20 000
# points).
# Usage: data/make_scans.sh [path/to/csgvox]
# PARTS (a folder of <part>/tree.json), POINTS, SCANNER_POINTS and SEED (of
# the first part; the noisy scans use SEED + 1000, the scanner scans
# SEED + 2000) change the defaults: data/, 10000, 20000, 1.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
csgvox=${1:-"$here/../build/app/csgvox"}
parts=${PARTS:-$here}
points=${POINTS:-10000}
scanner_points=${SCANNER_POINTS:-20000}
seed=${SEED:-1}
for tree in "$parts"/*/tree.json; do
  part=$(dirname "$tree")
  "$csgvox" sample "$tree" -o "$part/scan.ply" --points "$points" --seed "$seed" --quiet
  "$csgvox" sample "$tree" -o "$part/scan_noisy.ply" --points "$points" --noise 0.005 \
    --seed $((seed + 1000)) --quiet
  "$csgvox" sample "$tree" -o "$part/scan_scanner.ply" --scanner --points "$scanner_points" \
    --seed $((seed + 2000)) --quiet
  seed=$((seed + 1))
done
