"""The in-memory API against the Rust API and the command line, on real points."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

import sweeptin


def canonical(v: np.ndarray, t: np.ndarray) -> set[tuple[float, ...]]:
    """Triangles as sets of coordinates, each rotated to start at its smallest vertex."""
    out = set()
    for tri in v[t]:
        pts = [tuple(p) for p in tri]
        k = min(range(3), key=lambda i: pts[i][:2])
        out.add(tuple(x for p in pts[k:] + pts[:k] for x in p))
    return out


def test_arrays_equal_the_rust_api(small, rust_triangulate, tmp_path):
    _, xyz = small
    tin = sweeptin.triangulate(xyz)
    v, t, i = rust_triangulate(xyz, tmp_path)
    assert tin.vertices.dtype == np.float64 and tin.vertices.shape == v.shape
    assert tin.triangles.dtype == np.uint32 and tin.input_index.dtype == np.uint32
    assert np.array_equal(tin.vertices, v)
    assert np.array_equal(tin.triangles, t)
    assert np.array_equal(tin.input_index, i)
    assert tin.duplicates == 1  # the file's one duplicate (x, y)
    assert np.array_equal(tin.vertices, xyz[tin.input_index])
    # Read-only views owned by the TIN; a float64 C-contiguous input is not copied.
    assert not tin.vertices.flags.writeable
    assert tin.points is not None and tin.number_of_triangles() == len(t)
    # The same set in another order gives the same triangulation.
    rng = np.random.default_rng(1)
    shuffled = sweeptin.triangulate(xyz[rng.permutation(len(xyz))])
    assert np.array_equal(shuffled.vertices, tin.vertices)
    assert np.array_equal(shuffled.triangles, tin.triangles)


def test_duplicates_policy(small, rust_triangulate, tmp_path):
    _, xyz = small
    for policy in ("lowest", "highest"):
        tin = sweeptin.triangulate(xyz, duplicates=policy)
        v, t, i = rust_triangulate(xyz, tmp_path, policy)
        assert np.array_equal(tin.vertices, v) and np.array_equal(tin.input_index, i)


def test_the_same_triangles_as_the_streaming_cli(small, cli, tmp_path):
    path, xyz = small
    tin = sweeptin.triangulate(xyz)
    obj = tmp_path / "cli.obj"
    cli("tin", path, "-o", obj, "-q")
    lines = obj.read_text().splitlines()
    v = np.array([[float(x) for x in l.split()[1:4]] for l in lines if l.startswith("v ")])
    f = np.array([[int(x) - 1 for x in l.split()[1:4]] for l in lines if l.startswith("f ")])
    assert canonical(v, f) == canonical(tin.vertices, tin.triangles)


def test_interpolate_equals_cli_sample(small, cli, tmp_path):
    path, xyz = small
    tin = sweeptin.triangulate(xyz)
    rng = np.random.default_rng(7)
    lo, hi = xyz[:, :2].min(0), xyz[:, :2].max(0)
    q = np.vstack(
        [
            lo + rng.random((2000, 2)) * (hi - lo),
            xyz[:50, :2],  # on vertices
            (xyz[tin.input_index[tin.triangles[:50, 0]], :2] + xyz[tin.input_index[tin.triangles[:50, 1]], :2]) / 2,
            [[0.0, 0.0]],  # outside
        ]
    )
    z = tin.interpolate(q)
    csv = tmp_path / "q.csv"
    csv.write_text("".join(f"{float(x)!r},{float(y)!r}\n" for x, y in q))
    out = tmp_path / "z.csv"
    cli("sample", path, "--points", csv, "-o", out, "-q")
    want = [float(l.split(",")[2]) if l.split(",")[2] else float("nan") for l in out.read_text().splitlines()]
    assert np.isnan(z[-1])
    np.testing.assert_array_equal(z, np.array(want))
    # On a vertex, exactly its z.
    v = tin.vertices[:500]
    assert np.array_equal(tin.interpolate(v[:, :2]), v[:, 2])


def asc_cells(path) -> tuple[list[str], list[list[str]]]:
    lines = path.read_text().splitlines()
    return lines[:6], [l.split() for l in lines[6:]]


def shortest(a: np.ndarray) -> list[list[str]]:
    return [[np.format_float_positional(v, unique=True, trim="-") for v in row] for row in a]


@pytest.mark.parametrize("align", ["edges", "centres"])
def test_rasterize_equals_cli_dem(small, cli, tmp_path, align):
    path, xyz = small
    tin = sweeptin.triangulate(xyz)
    out = tmp_path / "dem.asc"
    cli("dem", path, "--cell", "0.5", "--align", align, "-o", out, "-q")
    header, cells = asc_cells(out)
    values, transform = tin.rasterize(0.5, align=align, nodata=-9999)
    assert values.dtype == np.float32
    assert shortest(values) == cells
    h = {l.split()[0].lower(): float(l.split()[1]) for l in header}
    assert (h["ncols"], h["nrows"]) == (values.shape[1], values.shape[0])
    x0 = h["xllcorner"] if "xllcorner" in h else h["xllcenter"] - 0.25
    y0 = h["yllcorner"] if "yllcorner" in h else h["yllcenter"] - 0.25
    assert transform[2] == x0 and transform[0] == 0.5
    assert transform[5] == y0 + 0.5 * values.shape[0]


def test_rasterize_edges_lattice(small):
    _, xyz = small
    tin = sweeptin.triangulate(xyz)
    values, t = tin.rasterize(1.0)  # edges, the default
    a, _, c, _, e, f = tuple(t)[:6]
    assert (a, e) == (1.0, -1.0) and c == int(c) and f == int(f)
    rows, cols = values.shape
    # Every cell is the TIN's value at its centre (the DEM sink and interpolate agree).
    xs = c + 0.5 + np.arange(cols)
    ys = f - 0.5 - np.arange(rows)
    gx, gy = np.meshgrid(xs, ys)
    z = tin.interpolate(np.column_stack([gx.ravel(), gy.ravel()])).astype(np.float32)
    np.testing.assert_array_equal(values.ravel(), z)
    # A 10 m box on multiples of the cell: 10 × 10 cells whose edges are the box.
    x0, y0 = 85710.0, 447210.0
    box, tb = tin.rasterize(1.0, bbox=(x0, y0, x0 + 10, y0 + 10))
    assert box.shape == (10, 10) and tuple(tb)[2] == x0 and tuple(tb)[5] == y0 + 10
    cen, tc = tin.rasterize(1.0, bbox=(x0, y0, x0 + 10, y0 + 10), align="centres")
    # Centres on multiples in [x0, x0 + 10) × (y0, y0 + 10]: edges half a cell outside.
    assert cen.shape == (10, 10) and tuple(tc)[2] == x0 - 0.5 and tuple(tc)[5] == y0 + 10.5
    with pytest.raises(sweeptin.OptionsError, match="multiple"):
        tin.rasterize(1.0, bbox=(x0 + 0.3, y0, x0 + 10, y0 + 10))
    snapped, ts = tin.rasterize(1.0, bbox=(x0 + 0.3, y0, x0 + 10, y0 + 10), snap=True)
    assert snapped.shape == (10, 10) and tuple(ts)[2] == x0
    with pytest.raises(sweeptin.OptionsError):
        tin.rasterize(1.0, align="corners")


def contour_set(fc: dict) -> list:
    """The contours' directed segments by level, sorted: the lines' geometry, whichever way
    pieces meeting at a vertex exactly at a level were joined (that depends on the order the
    triangles come in, which differs between the stream and memory)."""
    out = []
    for f in fc["features"]:
        c = [tuple(p) for p in f["geometry"]["coordinates"]]
        out += [(f["properties"]["elevation"], a, b) for a, b in zip(c, c[1:]) if a != b]
    return sorted(out)


def test_contours_equal_cli(small, cli, tmp_path):
    path, xyz = small
    tin = sweeptin.triangulate(xyz)
    fc = tin.contours(interval=0.5)
    assert fc["type"] == "FeatureCollection" and fc["features"][0]["geometry"]["type"] == "LineString"
    out = tmp_path / "c.geojson"
    cli("contours", path, "--interval", "0.5", "-o", out, "-q")
    assert contour_set(fc) == contour_set(json.loads(out.read_text()))


def test_breaklines(small):
    _, xyz = small
    # A polyline through existing points (indices) and one given as new vertices.
    tin = sweeptin.triangulate(xyz[:2000])
    hull = np.array([0, 10, 20])
    lo, hi = xyz[:2000, :2].min(0), xyz[:2000, :2].max(0)
    mid = (lo + hi) / 2
    line = np.array([[mid[0] - 3, mid[1], 1.0], [mid[0] + 3, mid[1] + 0.5, 1.0]])
    cdt = sweeptin.triangulate(xyz[:2000], breaklines=[hull, line])
    assert cdt.number_of_vertices() == tin.number_of_vertices() + 2
    edges = {tuple(sorted(e)) for tri in cdt.triangles for e in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0]))}
    vid = {int(i): k for k, i in enumerate(cdt.input_index)}
    for a, b in ((0, 10), (10, 20), (2000, 2001)):
        assert tuple(sorted((vid[a], vid[b]))) in edges or cdt.crossing_skipped > 0
    seg = np.array([[0, 5], [5, 9]], dtype=np.int64)
    assert sweeptin.triangulate(xyz[:2000], breaklines=seg).number_of_triangles() > 0
    with pytest.raises(sweeptin.OptionsError):
        sweeptin.triangulate(xyz[:10], breaklines=[np.array([0, 99])])


def test_write_ply_obj(small, tmp_path):
    _, xyz = small
    tin = sweeptin.triangulate(xyz[:1000])
    s = tin.write_ply(tmp_path / "a.ply")
    assert s["vertices"] == 1000 and s["triangles"] == tin.number_of_triangles()
    assert (tmp_path / "a.ply").read_bytes().startswith(b"ply\nformat binary_little_endian")
    tin.write_obj(tmp_path / "a.obj")
    with pytest.raises(sweeptin.OptionsError):
        tin.write_ply(tmp_path / "a.obj")


def test_errors_are_the_documented_exceptions():
    with pytest.raises(sweeptin.NoTriangleError) as e:
        sweeptin.triangulate(np.array([[0.0, 0, 0], [1, 1, 1]]))
    assert isinstance(e.value, ValueError) and isinstance(e.value, sweeptin.SweeptinError)
    with pytest.raises(sweeptin.NoTriangleError, match="collinear"):
        sweeptin.triangulate(np.array([[0.0, 0, 0], [1, 1, 1], [2, 2, 2]]))
    with pytest.raises(sweeptin.InputError, match="not finite") as e:
        sweeptin.triangulate(np.array([[0.0, 0, 0], [1, 0, 1], [0, 1, 2], [np.nan, 5, 5]]))
    assert e.value.index == 3
    with pytest.raises(sweeptin.InputError, match="outside the supported range"):
        sweeptin.triangulate(np.array([[0.0, 0, 0], [1, 0, 1], [0, 1, 2], [1e300, 5, 5]]))
    with pytest.raises(sweeptin.OptionsError):
        sweeptin.triangulate(np.zeros((5, 2)))
    with pytest.raises(sweeptin.OptionsError, match="duplicates"):
        sweeptin.triangulate(np.eye(3), duplicates="median")


def test_rasterize_without_affine_names_its_order_and_gives_gdals(monkeypatch):
    """Issue 41, item 16: without the `affine` package `rasterize` returned a bare 6-tuple in
    affine's order, easily taken for GDAL's geotransform. It is a named `Transform`, in
    affine's order (as `affine.Affine`), with `to_gdal()` on both."""
    tin = sweeptin.triangulate(np.array([[0.0, 0, 0], [10, 0, 1], [0, 10, 2], [10, 10, 3]]))
    _, with_affine = tin.rasterize(0.5)
    monkeypatch.setitem(sys.modules, "affine", None)  # `import affine` fails
    values, t = tin.rasterize(0.5)
    assert isinstance(t, sweeptin.Transform) and isinstance(t, tuple)
    assert (t.a, t.b, t.c, t.d, t.e, t.f) == (0.5, 0.0, 0.0, 0.0, -0.5, 10.0)
    assert tuple(t) == tuple(with_affine)[:6]
    # GDAL's order: origin x, cell width, row rotation, origin y, column rotation, cell height.
    assert t.to_gdal() == with_affine.to_gdal() == (0.0, 0.5, 0.0, 10.0, 0.0, -0.5)
    assert "Transform(a=0.5" in repr(t)
    assert values.shape == (20, 20)


def test_the_module_exports_its_api_only():
    """Issue 41, item 16: `sweeptin.np`, `sweeptin.os` and `sweeptin.json` were there (the
    module's own imports); every public name is now in `__all__`, and no module is one."""
    import types

    public = {n for n in dir(sweeptin) if not n.startswith("_")}
    assert not {"np", "os", "json", "Any", "Sequence"} & public
    assert not [n for n in public if isinstance(getattr(sweeptin, n), types.ModuleType)]
    # `annotations` is `from __future__ import annotations`, a compiler directive.
    assert public - {"annotations"} == set(sweeptin.__all__)
    assert all(hasattr(sweeptin, n) for n in sweeptin.__all__)
