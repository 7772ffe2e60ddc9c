"""Tests of the csgvox Python module against the command-line tool.

ctest runs them with PYTHONPATH holding the built module and CSGVOX_BINARY /
CSGVOX_DATA_DIR naming the csgvox executable and the bundled data.
"""

import json
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import csgvox

BINARY = os.environ.get("CSGVOX_BINARY", "csgvox")
DATA = os.environ.get("CSGVOX_DATA_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "data"))
SCAN = os.path.join(DATA, "wedge_block", "scan.ply")

BOX = json.dumps({"root": {"type": "box", "center": [0, 0, 0], "half_size": [1, 2, 3]}})


def cli(*args):
    return subprocess.run([BINARY, *args], capture_output=True, text=True)


def cli_error(*args):
    """The one-line message of a failing command, without 'csgvox: error: '."""
    r = cli(*args)
    assert r.returncode == 1, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("csgvox: error: "), r.stderr
    return lines[0][len("csgvox: error: "):]


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory):
    """The CLI's outputs for SCAN at res 32, seed 3, with the fitted values
    (the module's reconstruct gives the fitted tree)."""
    out = tmp_path_factory.mktemp("cli") / "wedge"
    r = cli(SCAN, "-o", str(out), "--res", "32", "--seed", "3", "--mesh-res", "32", "--quiet",
            "--raw-values")
    assert r.returncode == 0, r.stderr
    return out


def test_read_scan_gives_numpy_arrays():
    points, normals = csgvox.read_scan(SCAN)
    assert points.dtype == np.float64 and normals.dtype == np.float64
    assert points.shape == (10000, 3) and normals.shape == (10000, 3)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    # The file's own values: binary little-endian float x y z nx ny nz.
    with open(SCAN, "rb") as f:
        raw = f.read()
    body = raw[raw.index(b"end_header\n") + len(b"end_header\n"):]
    rows = np.frombuffer(body, dtype="<f4").reshape(10000, 6).astype(np.float64)
    assert np.array_equal(points, rows[:, :3])
    expected = rows[:, 3:] / np.linalg.norm(rows[:, 3:], axis=1, keepdims=True)
    assert np.allclose(normals, expected, rtol=0, atol=1e-12)


def test_reconstruct_from_arrays_gives_the_cli_tree(cli_run):
    points, normals = csgvox.read_scan(SCAN, seed=3)
    result = csgvox.reconstruct(points, normals, res=32, seed=3)
    with open(cli_run / "tree.json") as f:
        assert result.tree.to_json() == f.read()
    with open(cli_run / "report.json") as f:
        report = json.load(f)
    assert list(result.report.keys()) == list(report.keys())
    assert result.report["tree"] == report["tree"]
    assert result.report["parameters"] == report["parameters"]
    assert result.report["counts"] == report["counts"]
    assert result.report["metrics"]["voxel_iou"] == report["metrics"]["voxel_iou"]
    assert result.report["metrics"]["chamfer"] == pytest.approx(report["metrics"]["chamfer"])
    assert result.tree.primitives == report["tree"]["primitives"]
    with open(cli_run / "tree.scad") as f:
        assert result.tree.to_scad() == f.read()
    with open(cli_run / "tree.txt") as f:
        assert result.tree.to_text() == f.read()


def test_another_seed_is_used():
    points, normals = csgvox.read_scan(SCAN)
    a = csgvox.reconstruct(points, normals, res=32, seed=3)
    assert a.report["parameters"]["seed"] == 3
    assert a.report["parameters"]["res"] == 32


def test_normals_are_estimated_when_missing():
    points, _ = csgvox.read_scan(SCAN)
    result = csgvox.reconstruct(points, res=24)
    assert result.report["input"]["normals"] == "estimated"
    assert result.tree.primitives >= 1
    assert result.report["metrics"]["voxel_iou"] > 0.8


def test_tree_json_round_trip_and_evaluate():
    tree = csgvox.Tree.from_json(BOX)
    assert tree.primitives == 1 and tree.operations == 0
    again = csgvox.Tree.from_json(tree.to_json())
    assert again.to_json() == tree.to_json()
    pts = np.array([[0, 0, 0], [2, 0, 0], [0, 1.5, 0], [0, 0, -4]], dtype=np.float64)
    assert np.array_equal(tree.evaluate(pts), [1.0, -1.0, 0.5, -1.0])
    assert tree.evaluate(np.zeros((0, 3))).shape == (0,)


def test_evaluate_matches_the_scan_of_a_ground_truth_tree():
    with open(os.path.join(DATA, "wedge_block", "tree.json")) as f:
        tree = csgvox.Tree.from_json(f.read())
    points, normals = csgvox.read_scan(SCAN)
    d = tree.evaluate(points)
    assert d.shape == (len(points),)
    diagonal = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
    assert np.max(np.abs(d)) < 1e-6 * diagonal  # the clean scan lies on the surface
    # A step along the outward normal leaves the solid, a step against it enters.
    step = 0.01 * diagonal
    assert np.mean(tree.evaluate(points + step * normals) < 0) > 0.99
    assert np.mean(tree.evaluate(points - step * normals) > 0) > 0.99


def test_read_errors_have_the_cli_messages(tmp_path):
    missing = str(tmp_path / "missing.ply")
    with pytest.raises(csgvox.IoError) as e:
        csgvox.read_scan(missing)
    assert str(e.value) == cli_error(missing, "-o", str(tmp_path / "out"))
    assert isinstance(e.value, OSError)
    broken = tmp_path / "broken.ply"
    with open(SCAN, "rb") as f:
        broken.write_bytes(f.read(2000))
    with pytest.raises(csgvox.ParseError) as e:
        csgvox.read_scan(str(broken))
    assert str(e.value) == cli_error(str(broken), "-o", str(tmp_path / "out"))
    assert "truncated" in str(e.value)


def test_reconstruct_errors():
    with pytest.raises(csgvox.ParseError, match="^points: has 5 points; at least 100 are needed$"):
        csgvox.reconstruct(np.random.default_rng(1).random((5, 3)))
    with pytest.raises(csgvox.ParseError, match=r"expected an array of shape \(N, 3\)"):
        csgvox.reconstruct(np.zeros((10, 2)))
    with pytest.raises(ValueError, match="unknown method"):
        csgvox.reconstruct(np.zeros((200, 3)), method="magic")
    # Names and ranges are the command line's, checked before any work.
    with pytest.raises(ValueError, match=r"^unknown labelling method 'flood' \(winding or vote\)$"):
        csgvox.reconstruct(np.zeros((200, 3)), label="flood")
    with pytest.raises(ValueError, match=r"^unknown label boundary 'edge' \(centre or inside\)$"):
        csgvox.reconstruct(np.zeros((200, 3)), label_boundary="edge")
    with pytest.raises(ValueError, match=r"^res must be in \[8, 1024\]$"):
        csgvox.reconstruct(np.zeros((200, 3)), res=4)
    with pytest.raises(ValueError, match=r"^time_limit must be in \[0, 1e\+06\]$"):
        csgvox.reconstruct(np.zeros((200, 3)), time_limit=float("nan"))
    points, normals = csgvox.read_scan(SCAN)
    with pytest.raises(csgvox.ParseError, match="non-finite"):
        bad = points.copy()
        bad[7, 1] = np.nan
        csgvox.reconstruct(bad, normals)
    # Points in one plane are no solid: the CLI's message.
    flat = points.copy()
    flat[:, 2] = 0.0
    up = np.tile([0.0, 0.0, 1.0], (len(flat), 1))
    with pytest.raises(csgvox.ParseError, match="^points: .*one plane"):
        csgvox.reconstruct(flat, up, res=16)


def test_reconstruct_releases_the_gil():
    points, normals = csgvox.read_scan(SCAN)
    ticks = 0
    done = threading.Event()

    def work():
        csgvox.reconstruct(points, normals, res=32)
        done.set()

    worker = threading.Thread(target=work)
    start = time.monotonic()
    worker.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    worker.join()
    elapsed = time.monotonic() - start
    # With the GIL held for the whole reconstruction this loop could not run
    # (a tick or two before the worker takes it); released, it ticks about
    # every millisecond.
    assert elapsed > 0.2
    assert ticks >= 20


def test_solver_warnings_are_not_printed(capfd):
    # On this scan the fit of some surfaces is ill-conditioned at times;
    # Ceres then logs a warning per step it cannot take (about 35 lines
    # before the module set the solver's log as the command line does).
    points, normals = csgvox.read_scan(os.path.join(DATA, "regressions", "inversecsg-143-60k.ply"))
    csgvox.reconstruct(points, normals)
    err = capfd.readouterr().err
    assert "solver failure" not in err, err[:400]
