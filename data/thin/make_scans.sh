#!/usr/bin/env bash
# Regenerates the scans of the thin-feature parts: data/thin/<part>/scan.ply
# (clean) and scan_noisy.ply (Gaussian noise, sigma = 0.5 % of the diagonal),
# 20 000 points each with normals (thin features need the points), and
# scan_scanner.ply (the default turntable scanner model, docs/scanner.md: raw
# x y z, 20 000 points).
# Usage: data/thin/make_scans.sh [path/to/csgvox]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
PARTS=$here POINTS=20000 SCANNER_POINTS=20000 SEED=101 exec "$here/../make_scans.sh" "${1:-"$here/../../build/app/csgvox"}"
