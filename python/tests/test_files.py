"""The file and streaming API against the command line: the same bytes, the same numbers."""

from __future__ import annotations

import json

import numpy as np
import pytest

import sweeptin

from conftest import data


def test_dem_and_contours_are_the_cli_bytes(small, cli, tmp_path):
    path, _ = small
    py_dem, py_c = tmp_path / "py.tif", tmp_path / "py.geojson"
    s = sweeptin.dem(path, py_dem, cell=0.5, contours=py_c, interval=0.25, classes=[2])
    cli_dem, cli_c = tmp_path / "cli.tif", tmp_path / "cli.geojson"
    cli("dem", path, "--cell", "0.5", "--class", "2", "--contours", cli_c, "--interval", "0.25", "-o", cli_dem, "-q")
    assert py_dem.read_bytes() == cli_dem.read_bytes()
    assert py_c.read_bytes() == cli_c.read_bytes()
    d = s["products"]["dem"]
    assert d["cell"] == 0.5 and d["cols"] > 0 and d["crs"]
    assert s["run"]["points_read"] == 18392  # class 2 of the file
    # A box on the cell lattice, read with a bbox filter, and an ASCII grid.
    box = (85710.0, 447210.0, 85730.0, 447230.0)
    a, b = tmp_path / "a.asc", tmp_path / "b.asc"
    sweeptin.dem(path, a, cell=1, bbox=box)
    cli("dem", path, "--cell", "1", "--bbox", ",".join(map(str, box)), "-o", b, "-q")
    assert a.read_bytes() == b.read_bytes()
    with pytest.raises(sweeptin.OptionsError, match="align"):
        sweeptin.dem(path, tmp_path / "e.tif", align="corners")


@pytest.mark.parametrize(
    "align, raster",
    [("edges", {}), ("centres", {}), ("edges", {"format": "cog", "compress": "zstd"})],
)
def test_dem_alignments_and_cog_are_the_cli_bytes(small, cli, tmp_path, align, raster):
    path, _ = small
    py, c = tmp_path / "py.tif", tmp_path / "cli.tif"
    s = sweeptin.dem(path, py, cell=1, align=align, classes=[2], **raster)
    flags = [x for k, v in raster.items() for x in (f"--{k}", v)]
    cli("dem", path, "--cell", "1", "--align", align, "--class", "2", *flags, "-o", c, "-q")
    assert py.read_bytes() == c.read_bytes()
    d = s["products"]["dem"]
    # Edges on whole metres, or centres on them (the origin half a cell off the lattice).
    assert d["origin"][0] % 1 == (0.0 if align == "edges" else 0.5)


def test_contours_from_two_files_equal_cli(cli, tmp_path):
    files = [data("lidar/ahn3_delft_cropped_1.laz"), data("lidar/ahn3_delft_cropped_2.laz")]
    py, c = tmp_path / "py.geojson", tmp_path / "cli.geojson"
    sweeptin.contours(files, py, interval=1.0, classes=[2], crs="EPSG:28992")
    cli("contours", *files, "--interval", "1", "--class", "2", "--crs", "EPSG:28992", "-o", c, "-q")
    assert py.read_bytes() == c.read_bytes()
    assert "28992" in json.loads(py.read_text())["crs"]["properties"]["name"]


def test_volume_equals_cli(small, cli, tmp_path):
    path, _ = small
    s = sweeptin.volume(path, plane=1.0, classes=[2])
    v = s["products"]["volume"]
    out = json.loads(cli("volume", path, "--plane", "1", "--class", "2", "--json", "-q").stdout)
    for k in ("cut_volume", "fill_volume", "net_volume", "cut_area", "fill_area", "area"):
        assert v[k] == out[k], k


def test_tin_file_is_the_cli_bytes(small, cli, tmp_path):
    path, _ = small
    py, c = tmp_path / "py.ply", tmp_path / "cli.ply"
    s = sweeptin.tin(str(path), py, mem="64M")
    cli("tin", str(path), "-o", c, "--mem", "64M", "-q")
    assert py.read_bytes() == c.read_bytes()
    assert s["products"]["mesh"]["triangles"] == s["run"]["triangles"] > 0


def test_stream_triangles_are_the_tin(small, tmp_path):
    path, xyz = small
    tin = sweeptin.triangulate(xyz)
    it = sweeptin.stream_triangles(path, chunk=10_000)
    chunks = list(it)
    assert all(c.shape[1:] == (3, 3) and c.dtype == np.float64 for c in chunks)
    assert all(len(c) <= 10_000 for c in chunks) and len(chunks) > 1
    got = np.concatenate(chunks)
    assert len(got) == tin.number_of_triangles()

    def key(tris: np.ndarray) -> set:
        return {tuple(sorted(map(tuple, t))) for t in tris}

    assert key(got) == key(tin.vertices[tin.triangles])
    assert it.summary is not None and it.summary["triangles"] == len(got)
    # Stopping early stops the run (no hang, no error).
    first = next(iter(sweeptin.stream_triangles(path, chunk=100)))
    assert len(first) == 100


def test_file_errors(small, tmp_path):
    path, _ = small
    with pytest.raises(sweeptin.MissingFileError) as e:
        sweeptin.dem(tmp_path / "nope.laz", tmp_path / "x.tif")
    assert isinstance(e.value, FileNotFoundError) and str(e.value.path).endswith("nope.laz")
    link = tmp_path / "c.geojson"
    link.symlink_to(path)
    with pytest.raises(sweeptin.OptionsError, match="input"):
        sweeptin.contours(path, link)  # would overwrite its input, through the link
    with pytest.raises(sweeptin.NoTriangleError, match="class") as e:
        sweeptin.volume(path, plane=0, classes=[200])  # the filters leave nothing
    assert (e.value.kind, e.value.exit_code) == ("input", 3)
    # Outputs checked before any work, as the command line does (exit 4 there).
    with pytest.raises(sweeptin.MissingFileError) as e:
        sweeptin.dem(path, tmp_path / "no" / "dir" / "x.tif")
    assert (e.value.kind, e.value.exit_code) == ("output", 4)
    with pytest.raises(sweeptin.OptionsError, match="max-cells") as e:
        sweeptin.dem(path, tmp_path / "x.tif", cell=0.01, max_cells=1000)
    assert e.value.exit_code == 2
    # A tile side that is no size is refused whatever the engine (the sweep ignored it).
    for engine in ("sweep", "tiles"):
        with pytest.raises(sweeptin.OptionsError, match="--tile"):
            sweeptin.dem(path, tmp_path / "x.tif", cell=1, engine=engine, tile=0)
    bad = tmp_path / "bad.xyz"
    bad.write_text("0 0 0\n1 0 1\n0 1 oops\n")
    with pytest.raises(sweeptin.InputError) as e:
        sweeptin.tin(bad, tmp_path / "bad.ply")
    assert e.value.line == 3
    with pytest.raises(sweeptin.OptionsError):
        sweeptin.dem(path, tmp_path / "x.tif", cell=-1)
    with pytest.raises(sweeptin.OptionsError):
        sweeptin.tin(path, tmp_path / "x.ply", mem="lots")
    with pytest.raises(TypeError, match="unknown option"):
        sweeptin.tin(path, tmp_path / "x.ply", colour="red")
    assert not list(tmp_path.glob("x.*"))


def test_ctrl_c_stops_a_run_and_leaves_no_output(tmp_path):
    """SIGINT during `sweeptin.tin` on the ARSO crop (0.9M points): KeyboardInterrupt once the
    run has stopped (at its next triangle), and no file under the output's name."""
    import signal
    import subprocess
    import sys
    import time

    arso = data("lidar/arso_TM_511_122_sw_250m.laz")
    out = tmp_path / "arso.ply"
    # Python's own SIGINT handler, as an interactive session has it: a runner started in the
    # background (`cmd &` in a script) passes SIGINT on as ignored, and Python keeps it so.
    code = (
        "import signal, sweeptin, sys\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "print('started', flush=True)\n"
        "try:\n"
        f"    sweeptin.tin({str(arso)!r}, {str(out)!r})\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted'); sys.exit(3)\n"
    )
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "started"
    # The run takes seconds (3 s of CPU in the dev profile): half a second puts the signal in it.
    time.sleep(0.5)
    p.send_signal(signal.SIGINT)
    stdout, _ = p.communicate(timeout=300)
    assert p.returncode == 3 and "interrupted" in stdout, (p.returncode, stdout)
    assert not out.exists()
    assert not [f for f in tmp_path.iterdir() if f.name != "arso.ply"], list(tmp_path.iterdir())
