"""Tile plans from Python: the same plan.json as the command line, tasks run by either, a
mosaic equal to one run, and the Dask example with two worker processes."""

from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import pytest

import sweeptin

from conftest import REPO, data


@pytest.fixture(scope="module")
def ign():
    d = data("lidar/ign_50m_tiles")
    files = sorted(str(p) for p in Path(d).glob("*.laz"))
    assert len(files) == 6
    return files


def extent(plan: sweeptin.Plan) -> tuple[float, ...]:
    tiles = json.loads(Path(plan.path).read_text())["tiles"]
    return tuple(f(t["bounds"][k] for t in tiles) for k, f in ((0, min), (1, min), (2, max), (3, max)))


def test_a_python_plan_runs_anywhere_and_merges_to_one_run(ign, cli, tmp_path):
    contours = tmp_path / "planned.geojson"
    plan = sweeptin.plan(
        "dem", ign, tmp_path / "job", tile=50, cell=0.5, classes=[2], contours=contours,
        interval=0.25, buffer=2,
    )
    n = len(plan)
    assert n >= 6 and plan.tasks == range(n)
    assert pickle.loads(pickle.dumps(plan)).path == plan.path
    # The same job from the command line makes the same plan (but for who wrote it).
    cli("plan", "--buffer", "2", "dem", *ign, "--cell", "0.5", "--class", "2", "--contours", contours,
        "--interval", "0.25", "--tile", "50", "-o", tmp_path / "cli-job")
    ours = json.loads(Path(plan.path).read_text())
    theirs = json.loads((tmp_path / "cli-job" / "plan.json").read_text())
    for k in ("version", "command", "job", "files", "tile", "buffer", "cell", "tiles"):
        assert ours[k] == theirs[k], k
    # Half the tasks from Python, half from the command line, in any order.
    records = [sweeptin.run_task(plan, i, threads=1) for i in range(0, n, 2)]
    for i in range(1, n, 2):
        cli("run", plan.path, "--task", i, "-q", "--threads", "1")
    assert all(r["status"] in ("done", "empty") for r in records)
    again = sweeptin.run_task(plan, 0, resume=True)
    assert again == records[0]  # skipped: its record as it was
    py_mosaic = tmp_path / "py.tif"
    s = sweeptin.merge(plan, py_mosaic)
    # Empty tasks write no tile (their part of the mosaic is nodata).
    assert s["tasks"] == n and 0 < s["dem"]["tiles"] <= n and s["contours"]["features"] > 100
    cli_mosaic = tmp_path / "cli.tif"
    cli("merge", plan.path, "-o", cli_mosaic, "--contours", tmp_path / "cli.geojson")
    assert py_mosaic.read_bytes() == cli_mosaic.read_bytes()
    assert contours.read_bytes() == (tmp_path / "cli.geojson").read_bytes()
    # The mosaic is one run's file (its extent: the points kept); extent="tiles", the tiles'.
    single = tmp_path / "single.tif"
    sweeptin.dem(ign, single, cell=0.5, classes=[2])
    assert py_mosaic.read_bytes() == single.read_bytes()
    assert s["dem"]["extent"] == "data"
    tiles, boxed = tmp_path / "tiles.tif", tmp_path / "boxed.tif"
    assert sweeptin.merge(plan, tiles, extent="tiles")["dem"]["extent"] == "tiles"
    sweeptin.dem(ign, boxed, cell=0.5, bbox=extent(plan), classes=[2])
    assert tiles.read_bytes() == boxed.read_bytes()
    with pytest.raises(sweeptin.OptionsError, match="extent"):
        sweeptin.merge(plan, tmp_path / "x.tif", extent="everything")


def test_a_centre_aligned_cog_plan_is_the_cli_plan(ign, cli, tmp_path):
    """The DEM's alignment and the mosaic's format live in the plan's job: Python and the
    command line make the same job, and the mosaic (a COG by the plan) equals one run."""
    files = ign[:2]
    plan = sweeptin.plan(
        "dem", files, tmp_path / "job", tile=50, cell=0.5, align="centres", format="cog",
        classes=[2], buffer=2,
    )
    cli("plan", "--buffer", "2", "dem", *files, "--cell", "0.5", "--align", "centres",
        "--format", "cog", "--class", "2", "--tile", "50", "-o", tmp_path / "cli-job")
    ours = json.loads(Path(plan.path).read_text())
    theirs = json.loads((tmp_path / "cli-job" / "plan.json").read_text())
    assert ours["job"] == theirs["job"]
    assert ours["job"]["product"]["align"] == "centres"
    assert ours["job"]["product"]["raster"]["format"] == "cog"
    for i in plan.tasks:
        sweeptin.run_task(plan, i, threads=1)
    py_mosaic, cli_mosaic = tmp_path / "py.tif", tmp_path / "cli.tif"
    s = sweeptin.merge(plan, py_mosaic, hillshade=tmp_path / "shade.png")
    assert s["hillshade"]["shaded"] > 0 and (tmp_path / "shade.pgw").exists()
    cli("merge", plan.path, "-o", cli_mosaic)
    assert py_mosaic.read_bytes() == cli_mosaic.read_bytes()
    single = tmp_path / "single.tif"
    sweeptin.dem(files, single, cell=0.5, align="centres", format="cog", classes=[2])
    assert py_mosaic.read_bytes() == single.read_bytes()
    with pytest.raises(sweeptin.OptionsError, match="GeoTIFF"):
        sweeptin.merge(plan, tmp_path / "m.tif", format="asc")


def test_volume_plan_sums_exactly(ign, tmp_path):
    plan = sweeptin.plan("volume", ign[:2], tmp_path / "v", tile=50, plane=21.0, classes=[2])
    for i in plan.tasks:
        sweeptin.run_task(plan, i)
    v = sweeptin.merge(plan)["volume"]
    one = sweeptin.volume(ign[:2], plane=21.0, classes=[2])["products"]["volume"]
    for k in ("cut_volume", "fill_volume", "net_volume", "cut_area", "fill_area", "area"):
        assert v[k] == one[k], k


def test_tin_plan_merges_to_the_triangles_of_one_run(ign, tmp_path):
    plan = sweeptin.plan("tin", ign[:2], tmp_path / "t", tile=50, classes=[2])
    for i in plan.tasks:
        sweeptin.run_task(plan, i)
    s = sweeptin.merge(plan, tmp_path / "m.ply")["tin"]
    one = sweeptin.tin(ign[:2], tmp_path / "one.ply", classes=[2])
    mesh = one["products"]["mesh"]
    assert (s["triangles"], s["vertices"]) == (mesh["triangles"], mesh["vertices"])


def test_a_plan_with_3d_lines_is_the_cli_plan_and_lines_without_z_are_refused(ign, cli, tmp_path):
    """Breaklines and a hole with z go into the plan's job (version 3, each file by absolute path
    with its size and SHA-256), as from the command line; a line without z is refused, named."""
    lines = tmp_path / "lines.txt"
    lines.write_text("770505.25 6277503.5 21\n770595.75 6277596.25 21.4\n")
    hole = tmp_path / "hole.txt"
    hole.write_text("770560 6277530 21\n770575 6277530 21\n770575 6277545 21\n770560 6277530 21\n")
    plan = sweeptin.plan("dem", ign, tmp_path / "job", tile=50, cell=0.5, classes=[2],
                         breaklines=[lines], holes=hole)
    cli("plan", "dem", *ign, "--cell", "0.5", "--class", "2", "--breaklines", lines, "--holes", hole,
        "--tile", "50", "-o", tmp_path / "cli-job")
    ours = json.loads(Path(plan.path).read_text())
    theirs = json.loads((tmp_path / "cli-job" / "plan.json").read_text())
    assert ours["version"] == 3
    for k in ("version", "job", "tiles"):
        assert ours[k] == theirs[k], k
    assert ours["job"]["lines"]["holes"]["path"] == str(hole.resolve())
    assert len(ours["job"]["lines"]["breaklines"][0]["sha256"]) == 64
    flat = tmp_path / "flat.txt"
    flat.write_text("770505.25 6277503.5\n770595.75 6277596.25\n")
    with pytest.raises(sweeptin.OptionsError, match=r"flat.txt:1, vertex 0 .* has no z"):
        sweeptin.plan("dem", ign, tmp_path / "flat", tile=50, breaklines=[flat])


def test_plan_inputs_from_a_vpc_a_list_and_a_glob(ign, cli, tmp_path):
    """The library expands the inputs (as the command line does): a plan names every file of a
    .vpc, an @list or a glob, by absolute path."""
    vpc = tmp_path / "ign.vpc"
    cli("index", *ign, "-o", vpc)
    listing = tmp_path / "list.txt"
    listing.write_text("".join(f"{f}\n" for f in ign))
    want = sorted(os.path.realpath(f) for f in ign)
    for k, given in enumerate([[vpc], [f"@{listing}"], [str(Path(ign[0]).parent / "*.laz")]]):
        plan = sweeptin.plan("contours", given, tmp_path / f"p{k}", tile=50, interval=1)
        files = [f["path"] for f in json.loads(Path(plan.path).read_text())["files"]]
        assert sorted(files) == want, given


def test_plan_errors(ign, small, tmp_path):
    path, _ = small
    plan = sweeptin.plan("contours", [path], tmp_path / "c", tile=16, interval=1)
    with pytest.raises(sweeptin.OptionsError, match="does not exist"):
        sweeptin.run_task(plan, len(plan))
    with pytest.raises(sweeptin.OptionsError, match="have not finished"):
        sweeptin.merge(plan, tmp_path / "c.geojson")
    with pytest.raises(sweeptin.OptionsError, match="multiple"):
        sweeptin.plan("dem", ign, tmp_path / "d", tile=50.3, cell=0.5)
    with pytest.raises(sweeptin.OptionsError, match="plan makes"):
        sweeptin.plan("profile", ign, tmp_path / "d", tile=50)
    xyz = tmp_path / "p.xyz"
    xyz.write_text("0 0 0\n1 0 0\n0 1 0\n")
    with pytest.raises(sweeptin.InputError, match="LAS/LAZ"):
        sweeptin.plan("dem", [xyz], tmp_path / "d", tile=50)
    with pytest.raises(sweeptin.OptionsError, match="another plan"):
        sweeptin.plan("contours", [path], tmp_path / "c", tile=16, interval=2)


def test_run_task_takes_a_whole_task_index_only(small, tmp_path):
    """Issue 41, item 16: `run_task(p, 1.5)` ran task 1 (`int()` truncated it); a task index
    or thread count that is not an int is a TypeError, a negative one an OptionsError with
    the command line's exit code, and nothing runs."""
    path, _ = small
    plan = sweeptin.plan("contours", [path], tmp_path / "c", tile=16, interval=1)
    for i in (1.5, 1.0, "1", True, None):
        with pytest.raises(TypeError, match="whole number"):
            sweeptin.run_task(plan, i)
    with pytest.raises(TypeError, match="threads"):
        sweeptin.run_task(plan, 1, threads=2.0)
    for bad in (-1, -(2**70)):
        with pytest.raises(sweeptin.OptionsError, match=r"^i=-\d+: must be a whole number, 0 or more") as e:
            sweeptin.run_task(plan, bad)
        assert (e.value.kind, e.value.exit_code) == ("usage", 2)
    with pytest.raises(sweeptin.OptionsError, match="threads=-1"):
        sweeptin.run_task(plan, 1, threads=-1)
    assert not (tmp_path / "c" / "tiles").exists() or not any((tmp_path / "c" / "tiles").iterdir())
    # A numpy integer is a whole number.
    assert sweeptin.run_task(plan, np_int(1))["status"] in ("done", "empty")


def np_int(i: int):
    import numpy as np

    return np.int64(i)


def test_the_dask_example_runs_on_two_worker_processes(tmp_path):
    """Without files, on the repository's six IGN tiles (tests/data): the mosaic is the bytes of
    one run over the tiles' extent."""
    pytest.importorskip("dask.distributed") if os.environ.get("CI") not in ("true", "1") else None
    r = subprocess.run(
        [sys.executable, str(REPO / "examples" / "dask_plan.py"), "--workers", "2", "--out", str(tmp_path)],
        capture_output=True, text=True, timeout=600,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert "6 tasks" in r.stdout and "on 2 worker processes" in r.stdout, r.stdout
    assert "mosaic == single run (the same GeoTIFF bytes): True" in r.stdout


def test_the_dask_example_checks_against_every_point_past_the_tiles(tmp_path):
    """The ARSO corner at 1 m cells: 200 points lie a few cm outside the plan's tiles and shape
    the first row's and column's triangles. The mosaic holds them (the tasks read a buffer); the
    reference run must read them too (it read the tiles' box alone and said False, exit 1): one
    run over every point, whose GeoTIFF the mosaic is (`merge` writes one run's extent)."""
    pytest.importorskip("dask.distributed") if os.environ.get("CI") not in ("true", "1") else None
    arso = data("lidar/arso_TM_511_122_sw_250m.laz")
    r = subprocess.run(
        [sys.executable, str(REPO / "examples" / "dask_plan.py"), str(arso), "--cell", "1", "--tile", "125",
         "--workers", "2", "--out", str(tmp_path)],
        capture_output=True, text=True, timeout=600,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert "mosaic 250 x 250 cells from 4 tiles" in r.stdout, r.stdout
    assert "mosaic == single run (the same GeoTIFF bytes): True" in r.stdout, r.stdout
