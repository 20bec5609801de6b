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
    with pytest.raises(sweeptin.OptionsError, match="max_cells=") as e:
        sweeptin.dem(path, tmp_path / "x.tif", cell=0.01, max_cells=1000)
    assert e.value.exit_code == 2
    # A tile side that is no size is refused whatever the engine (the sweep ignored it).
    for engine in ("sweep", "tiles"):
        with pytest.raises(sweeptin.OptionsError, match="tile=0"):
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


def _cli_status(*args: object) -> tuple[int, str]:
    """The `sweeptin` binary's exit status and standard error (the `cli` fixture wants 0)."""
    import subprocess

    from conftest import built

    r = subprocess.run([str(built("sweeptin", "SWEEPTIN_BIN")), *map(str, args)], capture_output=True, text=True)
    return r.returncode, r.stderr


def _refused(call, *, cls=sweeptin.OptionsError) -> Exception:
    """The exception of ``call()``, which must be ``cls`` with the command line's kind and exit
    status (never ``None``)."""
    with pytest.raises(cls) as e:
        call()
    err = e.value
    assert isinstance(err, sweeptin.SweeptinError)
    assert (err.kind, err.exit_code) == ("usage", 2), (err, err.kind, err.exit_code)
    return err


def test_nonsense_numbers_are_refused_by_the_clis_own_checks(small, tmp_path):
    """Issue 41, item 3: `volume(plane=nan)` returned volumes of 0 (`inf`: nonsense) where
    `sweeptin volume --plane nan` exits 2. Every number of every file function goes through
    the library's checks that the command line uses, with the same class and exit code."""
    path, _ = small
    out = tmp_path / "x.tif"
    nan, inf = float("nan"), float("inf")
    cases = [
        # (Python call, the command line's flags for the same value)
        (lambda: sweeptin.volume(path, plane=nan), ["volume", path, "--plane", "nan"]),
        (lambda: sweeptin.volume(path, plane=inf), ["volume", path, "--plane", "inf"]),
        (lambda: sweeptin.volume(path, plane=-inf), ["volume", path, "--plane=-inf"]),
        (lambda: sweeptin.dem(path, out, cell=nan), ["dem", path, "-o", out, "--cell", "nan"]),
        (lambda: sweeptin.dem(path, out, cell=0), ["dem", path, "-o", out, "--cell", "0"]),
        (lambda: sweeptin.dem(path, out, cell=-1), ["dem", path, "-o", out, "--cell=-1"]),
        (lambda: sweeptin.dem(path, out, max_cells=0), ["dem", path, "-o", out, "--max-cells", "0"]),
        (lambda: sweeptin.dem(path, out, max_cells=-1), ["dem", path, "-o", out, "--max-cells=-1"]),
        (lambda: sweeptin.contours(path, tmp_path / "c.geojson", interval=0),
         ["contours", path, "-o", tmp_path / "c.geojson", "--interval", "0"]),
        (lambda: sweeptin.contours(path, tmp_path / "c.geojson", interval=nan),
         ["contours", path, "-o", tmp_path / "c.geojson", "--interval", "nan"]),
        (lambda: sweeptin.contours(path, tmp_path / "c.geojson", base=inf),
         ["contours", path, "-o", tmp_path / "c.geojson", "--base", "inf"]),
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", max_edge=nan),
         ["tin", path, "-o", tmp_path / "t.ply", "--max-edge", "nan"]),
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", max_edge=-1),
         ["tin", path, "-o", tmp_path / "t.ply", "--max-edge=-1"]),
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", tile=inf),
         ["tin", path, "-o", tmp_path / "t.ply", "--tile", "inf"]),
        # `mem=0` ran (as 0 bytes) where `--mem 0` is refused.
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", mem=0), ["tin", path, "-o", tmp_path / "t.ply", "--mem", "0"]),
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", mem=-1), ["tin", path, "-o", tmp_path / "t.ply", "--mem=-1"]),
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", mem=10**30),
         ["tin", path, "-o", tmp_path / "t.ply", "--mem", str(10**30)]),
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", threads=-1),
         ["tin", path, "-o", tmp_path / "t.ply", "--threads=-1"]),
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", threads=10**6),
         ["tin", path, "-o", tmp_path / "t.ply", "--threads", str(10**6)]),
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", bbox=(0, 0, nan, 1)),
         ["tin", path, "-o", tmp_path / "t.ply", "--bbox", "0,0,nan,1"]),
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", classes=[256]),
         ["tin", path, "-o", tmp_path / "t.ply", "--class", "256"]),
        (lambda: sweeptin.plan("volume", [path], tmp_path / "p", tile=16, plane=nan),
         ["plan", "volume", path, "--plane", "nan", "--tile", "16", "-o", tmp_path / "p"]),
        (lambda: sweeptin.plan("contours", [path], tmp_path / "p", tile=16, buffer=nan),
         ["plan", "--buffer", "nan", "contours", path, "--tile", "16", "-o", tmp_path / "p"]),
        (lambda: sweeptin.plan("contours", [path], tmp_path / "p", tile=nan),
         ["plan", "contours", path, "--tile", "nan", "-o", tmp_path / "p"]),
        (lambda: sweeptin.plan("contours", [path], tmp_path / "p", tile=16, mem=0),
         ["plan", "contours", path, "--tile", "16", "--mem", "0", "-o", tmp_path / "p"]),
    ]
    for k, (call, flags) in enumerate(cases):
        status, stderr = _cli_status(*flags)
        assert status == 2, (k, flags, stderr)
        _refused(call)
    # The same values in memory, and the stream's chunk.
    tin = sweeptin.triangulate(np.array([[0.0, 0, 0], [10, 0, 1], [0, 10, 2], [10, 10, 3]]))
    for call in (
        lambda: tin.rasterize(nan),
        lambda: tin.rasterize(0),
        lambda: tin.rasterize(1e-4),  # 10^10 cells: over max_cells, before any allocation
        lambda: tin.rasterize(1, max_cells=0),
        lambda: tin.contours(interval=0),
        lambda: tin.contours(interval=1, base=nan),
        lambda: sweeptin.stream_triangles(path, chunk=0),
        lambda: sweeptin.stream_triangles(path, chunk=-5),
    ):
        _refused(call)
    assert not list(tmp_path.iterdir())


def test_a_size_that_cannot_fit_is_refused_never_an_abort(small, tmp_path):
    """Issue 41, item 4: `stream_triangles([f], chunk=10**9)` allocated 72 GB up front and
    aborted the interpreter; a plan with `tile=1e-3` made a list of 10^10 tiles and aborted too
    (the command line as well). Run in a child process, so that an abort fails the test
    instead of ending it."""
    import subprocess
    import sys

    path, _ = small
    code = (
        "import sweeptin, sys\n"
        "def refused(call):\n"
        "    try:\n"
        "        call()\n"
        "    except sweeptin.OptionsError as e:\n"
        "        print(e.kind, e.exit_code, e, flush=True)\n"
        "    else:\n"
        "        print('accepted', flush=True)\n"
        f"p, d = {str(path)!r}, {str(tmp_path)!r}\n"
        "refused(lambda: next(iter(sweeptin.stream_triangles([p], chunk=10**9))))\n"
        "refused(lambda: next(iter(sweeptin.stream_triangles([p], chunk=10**6, mem='16M'))))\n"
        "refused(lambda: sweeptin.plan('contours', [p], d + '/p', tile=1e-3))\n"
        # The default chunk fits a small budget: not refused.
        "print(len(next(iter(sweeptin.stream_triangles([p], mem='16M')))), flush=True)\n"
    )

    def limit() -> None:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (8 << 30, 8 << 30))

    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, preexec_fn=limit)
    assert r.returncode == 0, (r.returncode, r.stdout, r.stderr[-2000:])
    lines = r.stdout.splitlines()
    assert len(lines) == 4, r.stdout
    assert lines[0].startswith("usage 2 chunk=1000000000:"), lines[0]
    assert lines[1].startswith("usage 2 chunk=1000000:") and "mem=" in lines[1], lines[1]
    assert lines[2].startswith("usage 2 tile=0.001 cuts the data"), lines[2]
    # 16 MiB: a quarter holds 58,254 triangles of 72 bytes.
    assert int(lines[3]) == (16 << 20) // 4 // 72, lines[3]
    status, stderr = _cli_status("plan", "contours", path, "--tile", "0.001", "-o", tmp_path / "q")
    assert status == 2 and "tasks a plan may have" in stderr, (status, stderr)


def test_classes_are_read_as_the_cli_reads_class(small, tmp_path):
    """Issue 41, item 16: `classes="29"` was classes 2 and 9 (a string iterated); it is class
    29, as `--class 29`; `"2,9"`, `2`, `[2, 9]` and numpy integers as expected."""
    path, _ = small
    with pytest.raises(sweeptin.NoTriangleError, match="by classes=") as e:
        sweeptin.volume(path, plane=0, classes="29")  # no point of class 29
    assert "--class" not in str(e.value)
    ground = sweeptin.volume(path, plane=0, classes=[2])["run"]["points_read"]
    for given in ("2", 2, np.uint8(2), [np.int64(2)], "2, 9", (2, 9)):
        assert sweeptin.volume(path, plane=0, classes=given)["run"]["points_read"] >= ground, given
    assert sweeptin.volume(path, plane=0, classes="2")["run"]["points_read"] == ground
    with pytest.raises(TypeError, match="classes"):
        sweeptin.volume(path, plane=0, classes=[2.5])
    _refused(lambda: sweeptin.volume(path, plane=0, classes="ground"))


def test_messages_name_the_python_parameters_not_the_cli_flags(small, tmp_path):
    """Issue 41, item 16: errors said "by --class", "--tile 0: …", "--max-cells 1000": from
    Python they name the parameter to change."""
    path, _ = small
    cases = [
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", tile=0), "tile=0: must be a positive size"),
        (lambda: sweeptin.dem(path, tmp_path / "x.tif", cell=0.01, max_cells=1000), "max_cells=1000"),
        (lambda: sweeptin.tin(path, tmp_path / "t.ply", max_edge=0), "max_edge=0: must be a positive length"),
        (lambda: sweeptin.contours(path, tmp_path / "c.geojson", interval=0), "(interval=0, base=0)"),
        (lambda: sweeptin.volume(path, plane=0, classes=[200]), "by classes="),
    ]
    for call, want in cases:
        with pytest.raises(sweeptin.SweeptinError) as e:
            call()
        assert want in str(e.value), str(e.value)
        assert "--" not in str(e.value).split("`")[0], str(e.value)
