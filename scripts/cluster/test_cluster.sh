#!/usr/bin/env bash
# Tests the cluster recipes on this machine: the GNU parallel job list (run
# by GNU parallel, or xargs -P without it) and the Slurm array script (its
# tasks run one after another with SLURM_ARRAY_TASK_ID set, as Slurm would),
# each merged by merge.sh, against `csgvox batch` on the same scans: the same
# rows (status, message, tree size, metrics) and bit-identical trees, and a
# second run of the tasks does nothing.
#
# Usage: test_cluster.sh CSGVOX DATA_DIR WORK_DIR
set -euo pipefail
if [[ $# -ne 3 ]]; then
  echo "usage: $0 CSGVOX DATA_DIR WORK_DIR" >&2
  exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
export CSGVOX=$1
data=$(cd "$2" && pwd)
work=$3
rm -rf "$work"
mkdir -p "$work/in"
work=$(cd "$work" && pwd)
in=$work/in
cp "$data/flange/scan.ply" "$in/flange.ply"
cp "$data/wedge_block/scan_noisy.ply" "$in/wedge_noisy.ply"
cp "$data/l_bracket/scan.ply" "$in/l_bracket.ply"
head -c 2000 "$data/knob/scan.ply" > "$in/broken.ply"  # header and a few points: truncated
options=(--res 32 --mesh-res 32)
fail() { echo "FAIL: $*" >&2; exit 1; }

# The reference: one batch on this machine.
"$CSGVOX" batch "$in" -o "$work/batch" --jobs 2 --quiet "${options[@]}" || true

# GNU parallel job list.
"$here/joblist.sh" "$work/parallel" "$in" -- "${options[@]}" > "$work/jobs.txt"
[[ $(wc -l < "$work/jobs.txt") -eq 4 ]] || fail "job list has $(wc -l < "$work/jobs.txt") lines, expected 4"
run_jobs() {
  if command -v parallel > /dev/null; then
    parallel --will-cite --jobs 2 < "$work/jobs.txt" || true
  else
    xargs -P 2 -I{} sh -c {} < "$work/jobs.txt" || true
  fi
}
run_jobs
"$here/merge.sh" "$work/parallel" 4

# Slurm job array, its tasks run here.
tasks=$("$CSGVOX" batch --list -o "$work/slurm" "$in" | wc -l)
[[ $tasks -eq 4 ]] || fail "batch --list gives $tasks scans, expected 4"
for ((i = 1; i <= tasks; i++)); do
  SLURM_ARRAY_TASK_ID=$i SLURM_CPUS_PER_TASK=1 bash "$here/slurm.sbatch" "$work/slurm" "$in" \
    -- "${options[@]}" || true
done
"$here/merge.sh" "$work/slurm" "$tasks"

# Running the tasks again does nothing: no new row, no output rewritten.
before=$(find "$work/parallel" -name tree.json -exec stat -c '%n %.9Y' {} + | sort)
run_jobs
"$here/merge.sh" "$work/parallel" 4
after=$(find "$work/parallel" -name tree.json -exec stat -c '%n %.9Y' {} + | sort)
[[ $before == "$after" ]] || fail "a second run of the job list rewrote outputs"

python3 - "$work" << 'PY'
import json, os, sys, filecmp
work = sys.argv[1]
def rows(name):
    with open(os.path.join(work, name, "summary.jsonl")) as f:
        out = {}
        for line in f:
            r = json.loads(line)
            out[r["path"]] = r
        return out, sum(1 for _ in open(os.path.join(work, name, "summary.jsonl")))
ref, n = rows("batch")
assert n == 4 and len(ref) == 4, f"batch wrote {n} rows"
assert sorted(r["status"] for r in ref.values()) == ["error", "ok", "ok", "ok"], ref
broken = os.path.join(work, "in", "broken.ply")
assert ref[broken]["error"].startswith(broken + ": truncated"), ref[broken]
for name in ("parallel", "slurm"):
    got, n = rows(name)
    assert n == 4, f"{name}: {n} rows, expected 4"
    assert got.keys() == ref.keys(), (name, got.keys())
    for scan, r in ref.items():
        g = got[scan]
        for key in ("status", "primitives", "operations", "chamfer", "chamfer_relative", "voxel_iou"):
            assert g[key] == r[key], (name, scan, key, g[key], r[key])
        # The same place under each output folder, the same message.
        assert os.path.relpath(g["output"], os.path.join(work, name)) == \
            os.path.relpath(r["output"], os.path.join(work, "batch")), (g, r)
        assert g["error"] == r["error"], (g, r)
        if r["status"] == "ok":
            assert filecmp.cmp(os.path.join(r["output"], "tree.json"),
                               os.path.join(g["output"], "tree.json"), shallow=False), (name, scan)
    with open(os.path.join(work, name, "summary.csv")) as f:
        lines = f.read().splitlines()
    assert lines[0].startswith("path,output,status,error,"), lines[0]
    assert len(lines) == 5, f"{name}: summary.csv has {len(lines)} lines"
print("cluster recipes: parallel and slurm rows match the batch")
PY
