#!/usr/bin/env python3
"""Markdown table of `csgvox compare` runs on the bundled scans.

Usage: scripts/compare-table.py BINARY OUTDIR
OUTDIR holds one folder per scan (PART or PART-noisy) as written by
scripts/compare-all.sh. Per method: wall seconds, primitives/operations,
volumetric IoU against the part's true tree (data/PART/tree.json, through
`csgvox eval --reference`) and Chamfer distance in % of the diagonal.
"""
import json
import pathlib
import subprocess
import sys

binary, out = sys.argv[1], pathlib.Path(sys.argv[2])
data = pathlib.Path(__file__).resolve().parent.parent / "data"
rows = sorted(out.glob("*/compare.json"))
methods = []
for r in rows:
    for m in json.loads(r.read_text())["rows"]:
        if m["method"] not in methods:
            methods.append(m["method"])


def true_iou(scan_dir, method, part):
    tree = scan_dir / method / "tree.json"
    truth = data / part / "tree.json"
    if not tree.exists() or not truth.exists():
        return None
    scan = data / part / ("scan_noisy.ply" if scan_dir.name.endswith("-noisy") else "scan.ply")
    res = subprocess.run([binary, "eval", str(tree), str(scan), "--reference", str(truth),
                          "--json", "-q", "--surface-samples", "1000"],
                         capture_output=True, text=True, check=True)
    return json.loads(res.stdout)["iou_reference"]


print("| scan | " + " | ".join(f"{m}: s · prims/ops · IoU · Chamfer %D" for m in methods) + " |")
print("|---|" + "---|" * len(methods))
for r in rows:
    part = r.parent.name.removesuffix("-noisy")
    by = {m["method"]: m for m in json.loads(r.read_text())["rows"]}
    cells = [r.parent.name]
    for m in methods:
        x = by.get(m)
        if not x:
            cells.append("—")
            continue
        iou = true_iou(r.parent, m, part)
        cells.append(f'{x["wall_s"]:.1f} · {x["primitives"]}/{x["operations"]} · '
                     f'{iou:.3f} · {100 * x["chamfer_relative"]:.2f}' if iou is not None else
                     f'{x["wall_s"]:.1f} · {x["primitives"]}/{x["operations"]} · — · '
                     f'{100 * x["chamfer_relative"]:.2f}')
    print("| " + " | ".join(cells) + " |")
