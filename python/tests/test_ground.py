"""sweeptin.ground and sweeptin.height against the command line: the same classes, bytes and
heights."""

from __future__ import annotations

import json
from pathlib import Path

import laspy
import numpy as np
import pytest

import sweeptin

from conftest import data


@pytest.fixture(scope="module")
def raw():
    path = data("lidar/startinpy_small.laz")
    las = laspy.read(path)
    xyz = np.column_stack([las.x, las.y, las.z]).astype(np.float64)
    classes = np.asarray(las.classification, dtype=np.uint8)
    withheld = np.asarray(las.withheld, dtype=bool)
    return path, xyz, classes, withheld


def test_ground_on_arrays_gives_the_classes_the_cli_writes(raw, cli, tmp_path):
    path, xyz, classes, withheld = raw
    out = tmp_path / "g.laz"
    cli("ground", path, "-o", out, "-q", "--town")
    want = np.asarray(laspy.read(out).classification, dtype=np.uint8)
    got = sweeptin.ground(xyz[:, 0], xyz[:, 1], xyz[:, 2], classes=classes, withheld=withheld, preset="town")
    assert got.dtype == np.uint8 and got.shape == (len(xyz),)
    assert np.array_equal(got, want)
    # One (n, 3) array works too; without classes every point starts as class 0.
    got0 = sweeptin.ground(xyz, step=10)
    assert np.array_equal(got0 == 2, want == 2)
    with pytest.raises(sweeptin.OptionsError, match="max-angle"):
        sweeptin.ground(xyz, max_angle=90)
    with pytest.raises(sweeptin.OptionsError, match="preset"):
        sweeptin.ground(xyz, preset="moon")


def test_ground_and_height_on_files_are_the_cli_bytes(raw, cli, tmp_path):
    path, *_ = raw
    a, b = tmp_path / "py.laz", tmp_path / "cli.laz"
    s = sweeptin.ground(path, output=a, step=10, mem="64M")
    cli("ground", path, "-o", b, "-q", "--step", "10")
    assert a.read_bytes() == b.read_bytes()
    assert s["points"] == 39233 and s["ground"] > 0 and len(s["files"]) == 1
    # Heights above the ground found on the fly, and above the class-2 points of a file.
    ha, hb = tmp_path / "hpy.laz", tmp_path / "hcli.laz"
    sweeptin.height(path, output=ha, ground=True, step=10)
    cli("height", path, "--ground", "--step", "10", "-o", hb, "-q")
    assert ha.read_bytes() == hb.read_bytes()
    hc, hd = tmp_path / "hc.laz", tmp_path / "hd.laz"
    sweeptin.height(b, output=hc)
    cli("height", b, "-o", hd, "-q")
    assert hc.read_bytes() == hd.read_bytes()
    with pytest.raises(sweeptin.OptionsError, match="ground=True"):
        sweeptin.height(path, output=tmp_path / "x.laz", step=10)


def test_ground_to_a_copc_file_is_the_cli_bytes(cli, tmp_path):
    # An output named .copc.laz is a COPC file (the points in octree order), as on the
    # command line; a point format with NIR is refused before the work.
    path = data("lidar/lidR_Topography.laz")
    a, b = tmp_path / "py.copc.laz", tmp_path / "cli.copc.laz"
    s = sweeptin.ground(path, output=a)
    cli("ground", path, "-o", b, "-q")
    assert a.read_bytes() == b.read_bytes()
    assert s["files"][0]["output"] == str(a) and s["files"][0]["bytes"] == a.stat().st_size
    assert laspy.read(a).header.point_format.id == 6
    with pytest.raises(sweeptin.OptionsError, match="NIR"):
        sweeptin.ground(data("lidar/startinpy_small.laz"), output=tmp_path / "s.copc.laz")


def test_height_on_arrays_is_the_cli_height_above_ground(raw, cli, tmp_path):
    path, xyz, classes, withheld = raw
    out = tmp_path / "h.laz"
    cli("height", path, "--ground", "-o", out, "-q")
    want = np.asarray(laspy.read(out)["HeightAboveGround"], dtype=np.float64)
    got = sweeptin.height(xyz, classes=classes, withheld=withheld, ground=True)
    assert got.shape == want.shape
    # The same ground and triangles; the in-memory plane value differs in the last bits (laspy's
    # coordinates and Tin.interpolate's arithmetic), NaN at the same points.
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
    # The file's own class 2 as the ground.
    out2 = tmp_path / "h2.laz"
    cli("height", path, "-o", out2, "-q")
    want2 = np.asarray(laspy.read(out2)["HeightAboveGround"], dtype=np.float64)
    np.testing.assert_allclose(sweeptin.height(xyz, classes=classes, withheld=withheld), want2, rtol=0, atol=1e-9)


def test_products_with_ground_are_the_cli_bytes(raw, cli, tmp_path):
    path, *_ = raw
    # dem, contours and tin with ground=True: the command line's --ground, byte for byte.
    a, b = tmp_path / "py.tif", tmp_path / "cli.tif"
    s = sweeptin.dem(path, a, cell=1.0, ground=True, step=10, mem="64M")
    cli("dem", path, "--ground", "--step", "10", "--cell", "1", "--mem", "64M", "-o", b, "-q")
    assert a.read_bytes() == b.read_bytes()
    g = s["run"]["ground"]
    assert g["points"] == 39233 and 0 < g["ground"] < 39233 and g["block"] > 0
    ca, cb = tmp_path / "py.geojson", tmp_path / "cli.geojson"
    sweeptin.contours(path, ca, interval=1.0, ground=True, preset="town")
    cli("contours", path, "--ground", "--town", "--interval", "1", "-o", cb, "-q")
    assert ca.read_bytes() == cb.read_bytes()
    ta, tb = tmp_path / "py.ply", tmp_path / "cli.ply"
    t = sweeptin.tin(str(path), ta, ground=True, step=10, classes=[1, 2])
    cli("tin", str(path), "--ground", "--step", "10", "--class", "1,2", "-o", tb, "-q")
    assert ta.read_bytes() == tb.read_bytes()
    assert t["run"]["ground"]["ground"] == g["ground"]
    # Without ground=True the filter's parameters are refused, as the command line refuses them.
    with pytest.raises(sweeptin.OptionsError, match="ground=True"):
        sweeptin.dem(path, tmp_path / "x.tif", step=10)


def test_a_ground_plan_of_points_gives_every_point_the_class_of_one_ground_run(raw, cli, tmp_path):
    path, *_ = raw
    plan = sweeptin.plan("ground", [path], tmp_path / "job", tile=30, step=10, reset=True)
    assert json.loads(Path(plan.path).read_text())["job"]["product"]["kind"] == "ground"
    for i in plan.tasks:
        sweeptin.run_task(plan, i)
    merged, vpc, single = tmp_path / "m.laz", tmp_path / "m.vpc", tmp_path / "one.laz"
    s = sweeptin.merge(plan, merged)
    sweeptin.merge(plan, vpc)
    cli("ground", path, "-o", single, "-q", "--step", "10", "--reset")

    def keyed(las):
        return sorted(zip(las.X.tolist(), las.Y.tolist(), las.Z.tolist(), las.gps_time.tolist(),
                          np.asarray(las.classification).tolist()))

    want = keyed(laspy.read(single))
    assert s["points"]["points"] == len(want)
    assert keyed(laspy.read(merged)) == want
    with pytest.raises(sweeptin.OptionsError, match="buffer"):
        sweeptin.plan("ground", [path], tmp_path / "j3", tile=30, buffer=5)


def test_a_ground_plan_merges_into_one_ground_run(raw, tmp_path):
    path, *_ = raw
    plan = sweeptin.plan("dem", [path], tmp_path / "job", tile=30, cell=1.0, ground=True, step=10)
    assert json.loads(Path(plan.path).read_text())["job"]["ground"]["step"] == 10
    for i in plan.tasks:
        sweeptin.run_task(plan, i)
    merged, single = tmp_path / "m.tif", tmp_path / "one.tif"
    sweeptin.merge(plan, merged)
    sweeptin.dem(path, single, cell=1.0, ground=True, step=10)
    assert merged.read_bytes() == single.read_bytes()
    with pytest.raises(TypeError, match="colour"):
        sweeptin.plan("dem", [path], tmp_path / "j2", tile=30, ground=True, colour="red")
