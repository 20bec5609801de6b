"""sweeptin: exact, bounded-memory Delaunay TINs and terrain products from lidar.

Three ways in, as in pdal-python:

* **Whole arrays in memory**: :func:`triangulate` an ``(n, 3)`` array into a :class:`Tin`,
  then :meth:`Tin.interpolate`, :meth:`Tin.rasterize` (array + affine transform for rasterio),
  :meth:`Tin.contours` (GeoJSON-like dicts) or :meth:`Tin.write` (PLY, OBJ, LandXML).
* **A chunk iterator**: :func:`stream_triangles` yields the final triangles of a streaming run
  over LAS/LAZ/XYZ files as numpy chunks, in bounded memory.
* **Run to completion on files**: :func:`dem`, :func:`contours`, :func:`volume` and :func:`tin`
  do what the command line does, with the same bounded memory and the same output bytes.
* **Ground**: :func:`ground` classifies the ground (numpy arrays → classes, or files → files
  with their new classes, as ``sweeptin ground``) and :func:`height` gives heights above it
  (arrays → heights, or files → files with ``HeightAboveGround``, as ``sweeptin height``).

And tile plans for Dask or any batch engine: :func:`plan`, :func:`run_task`, :func:`merge` over
the same ``plan.json`` as ``sweeptin plan/run/merge``.

The file functions take these input options (keyword only), as the command line does:
``classes`` (kept classification codes: ``[2, 9]``, ``2``, or ``"2,9"`` as ``--class``
takes them, so ``"29"`` is class 29), ``returns`` (``"all"``, ``"first"``, ``"last"``),
``keep_withheld``, ``bbox`` (``(xmin, ymin, xmax, ymax)``), ``duplicates`` (``"first"``,
``"last"``, ``"lowest"``, ``"highest"``), ``breaklines`` (files), ``trim_boundary``, ``holes``,
``max_edge``, ``mem`` (sort budget: bytes or ``"512M"``; default 1 GiB, or under an
address-space limit what it leaves beside the program), ``tmp_dir``,
``engine`` (``"auto"``, the default: exact tiles on every core for LAS/LAZ points without
breaklines or trimming polygons, one streaming sweep otherwise; ``"tiles"``; ``"sweep"``),
``threads``, ``tile``, ``crs`` (``"EPSG:2154"`` or WKT) and ``progress`` (a progress bar on
stderr). Every value is checked by the library's own configuration, as the command line's
flags are, with the same errors (``mem=0``, ``plane=nan``, ``tile=-5``: :class:`OptionsError`,
``exit_code`` 2, the message naming the parameter); a count (``threads``, ``max_cells``,
``chunk``, a task's index) must be an ``int`` (``TypeError`` otherwise).

Errors raise the exceptions of :mod:`sweeptin._errors` (all :class:`SweeptinError`). The GIL is
released while the library works, so threads (and Dask's threaded scheduler) run in parallel.
"""

from __future__ import annotations

import json as _json
import operator as _operator
import os as _os
import re as _re
import typing as _typing

import numpy as _np

from . import _sweeptin as _native
from ._errors import (
    FileError,
    InputError,
    InternalError,
    MissingFileError,
    NoTriangleError,
    OptionsError,
    OutOfMemoryError,
    OutputError,
    SweeptinError,
)

__version__: str = _native.__version__

PathLike = _typing.Union[str, "_os.PathLike[str]"]
Files = _typing.Union[PathLike, _typing.Sequence[PathLike]]

__all__ = [
    "Tin",
    "Transform",
    "triangulate",
    "dem",
    "contours",
    "volume",
    "tin",
    "stream_triangles",
    "ground",
    "height",
    "Plan",
    "plan",
    "run_task",
    "merge",
    "SweeptinError",
    "InputError",
    "NoTriangleError",
    "OptionsError",
    "FileError",
    "MissingFileError",
    "OutputError",
    "OutOfMemoryError",
    "InternalError",
    "PathLike",
    "Files",
]


class Transform(_typing.NamedTuple):
    """A raster's affine transform in the order of the ``affine`` package and rasterio,
    ``(a, b, c, d, e, f)``: ``x = a*col + b*row + c``, ``y = d*col + e*row + f`` (of a cell's
    corner; ``c, f`` the raster's north-west corner, ``a`` the cell size, ``e`` minus it).
    NOT GDAL's geotransform order: :meth:`to_gdal` gives that, ``(c, a, b, f, d, e)``, as
    ``affine.Affine.to_gdal`` does."""

    a: float
    b: float
    c: float
    d: float
    e: float
    f: float

    def to_gdal(self) -> tuple[float, float, float, float, float, float]:
        """GDAL's geotransform ``(c, a, b, f, d, e)`` (``SetGeoTransform``'s order)."""
        return (self.c, self.a, self.b, self.f, self.d, self.e)


def _transform(t: _typing.Sequence[float]) -> _typing.Any:
    """``affine.Affine`` when the package is installed (what rasterio uses), else a
    :class:`Transform`: the same order ``(a, b, c, d, e, f)``, and ``to_gdal()`` on both."""
    try:
        from affine import Affine
    except ImportError:
        return Transform(*(float(v) for v in t))
    return Affine(*t)


def _whole(v: _typing.Any, name: str) -> int:
    """``v`` as an int: ``TypeError`` for anything but a whole number (``1.5``, ``"3"``,
    ``True``), as Python's own ``range`` or list indices do. Its range is the library's to
    check (beyond 64 bits it is clamped, still out of any range)."""
    if isinstance(v, bool) or not hasattr(type(v), "__index__"):
        raise TypeError(f"{name} must be a whole number (an int), not {v!r}")
    return max(-(2**63), min(_operator.index(v), 2**63 - 1))


def _classes(classes: _typing.Any) -> list[int] | None:
    """The classification codes to keep, parsed as ``--class`` parses them: ``"2,9"`` (or
    ``"29"``, class 29), one code ``2``, or codes ``[2, 9]``."""
    if classes is None:
        return None
    if isinstance(classes, str):
        text = classes
    elif hasattr(type(classes), "__index__") and not isinstance(classes, bool):
        text = str(_whole(classes, "classes"))
    else:
        text = ",".join(str(_whole(c, "classes")) for c in classes)
    return list(_named("classes", classes, _native.parse_classes, text))


def _named(name: str, given: _typing.Any, parse: _typing.Any, text: str) -> _typing.Any:
    """``parse(text)``, the library's parser of a flag's value; its error names the parameter
    as the command line's names the flag (``invalid value '0' for '--mem'``)."""
    try:
        return parse(text)
    except OptionsError as e:
        raise OptionsError(f"{name}={given!r}: {e}") from None


def _points(a: _typing.Any, cols: int, what: str) -> _np.ndarray:
    """``a`` as a C-contiguous float64 ``(n, cols)`` array (no copy when it already is one)."""
    arr = _np.ascontiguousarray(a, dtype=_np.float64)
    if arr.ndim != 2 or arr.shape[1] < cols:
        raise OptionsError(f"{what} must be an (n, {cols}) array, not shape {arr.shape}")
    if arr.shape[1] != cols:
        arr = _np.ascontiguousarray(arr[:, :cols])
    return arr


class Tin:
    """A Delaunay triangulation in memory, made by :func:`triangulate`.

    Attributes (read-only numpy arrays, owned by the TIN, not copies):

    * ``vertices``: ``(n, 3)`` float64, the distinct points ``[x, y, z]`` exactly as given, in
      sweep order (by ``y``, then ``x``);
    * ``triangles``: ``(m, 3)`` uint32, counter-clockwise triples of indices into ``vertices``;
    * ``input_index``: ``(n,)`` uint32, for every vertex the row of the input it is.

    ``points`` is ``vertices`` (startinpy's name).
    """

    __slots__ = ("_tin",)

    def __init__(self, native: _typing.Any) -> None:
        self._tin = native

    @property
    def vertices(self) -> _np.ndarray:
        return self._tin.vertices

    points = vertices

    @property
    def triangles(self) -> _np.ndarray:
        return self._tin.triangles

    @property
    def input_index(self) -> _np.ndarray:
        return self._tin.input_index

    @property
    def duplicates(self) -> int:
        """Input points merged away as exact (x, y) duplicates."""
        return int(self._tin.duplicates)

    @property
    def crossing_skipped(self) -> int:
        """Breakline segments left out because they cross another one."""
        return int(self._tin.crossing_skipped)

    def number_of_vertices(self) -> int:
        return int(self._tin.vertices.shape[0])

    def number_of_triangles(self) -> int:
        return int(self._tin.triangles.shape[0])

    def __repr__(self) -> str:
        return f"<sweeptin.Tin: {self.number_of_vertices()} vertices, {self.number_of_triangles()} triangles>"

    def interpolate(self, xy: _typing.Any) -> _np.ndarray:
        """Heights at the points ``xy`` (``(k, 2)``; more columns are ignored) by linear
        interpolation in the TIN; NaN outside it. A point exactly on an edge or a vertex gets
        the value of that edge or vertex alone, as the DEM and ``sweeptin sample`` do."""
        return self._tin.interpolate(_points(xy, 2, "xy"))

    def rasterize(
        self,
        cell: float,
        bbox: _typing.Sequence[float] | None = None,
        align: str = "edges",
        *,
        nodata: float = float("nan"),
        snap: bool = False,
        max_cells: int = 1 << 30,
    ) -> tuple[_np.ndarray, _typing.Any]:
        """The DEM of the TIN: ``(values, transform)``.

        ``values`` is a float32 ``(rows, cols)`` array, row 0 the northern one, each cell the
        TIN's height at the cell's centre (``nodata`` outside the TIN); ``transform`` is the
        affine transform rasterio expects, in the ``affine`` package's order
        ``(a, b, c, d, e, f)`` (``x = a*col + b*row + c``, ``y = d*col + e*row + f``):
        an ``affine.Affine`` when that package is installed, else a :class:`Transform` (a named
        tuple in the same order). Not GDAL's geotransform order: ``transform.to_gdal()`` gives
        ``(c, a, b, f, d, e)`` for ``SetGeoTransform``, on both.

        ``align="edges"`` (default): cell edges on multiples of ``cell`` (GDAL's ``-tap``): a
        1 km tile at 1 m is 1000 × 1000 cells. ``align="centres"``: cell centres on multiples
        (IGN's LiDAR HD lattice). The same lattices as ``sweeptin dem --align``, computed by
        the library's ``GridPlan``. ``bbox=(xmin, ymin, xmax, ymax)``
        with sides on multiples of ``cell`` (or ``snap=True`` to round them outwards); without
        it, the cells whose centres lie within the data's bounds. The values are computed by
        the library's DEM sink, as ``sweeptin dem`` computes them. ``max_cells`` as in
        :func:`dem`: a larger raster is refused (:class:`OptionsError`) before it is allocated.
        """
        b = None if bbox is None else [float(v) for v in bbox]
        n = _whole(max_cells, "max_cells")
        values, t = self._tin.rasterize(float(cell), b, align, float(nodata), bool(snap), n)
        return values, _transform(t)

    def contours(self, interval: float = 1.0, base: float = 0.0) -> dict[str, _typing.Any]:
        """Contour lines at ``base + k × interval`` as a GeoJSON-like FeatureCollection dict:
        LineString features with properties ``elevation`` and ``closed`` (higher ground on the
        left), the same lines ``sweeptin contours`` writes."""
        return _json.loads(self._tin.contours_geojson(float(interval), float(base)))

    def write(self, path: PathLike, *, crs: str | None = None) -> dict[str, int]:
        """Writes the mesh: ``.ply`` (binary PLY), ``.obj``, ``.xml`` (LandXML) or ``.stin``."""
        v, t, b = self._tin.write(_os.fspath(path), crs)
        return {"vertices": v, "triangles": t, "bytes": b}

    def write_ply(self, path: PathLike) -> dict[str, int]:
        """Writes a binary PLY (startinpy's name)."""
        return self.write(_with_extension(path, ".ply"))

    def write_obj(self, path: PathLike) -> dict[str, int]:
        """Writes a Wavefront OBJ (startinpy's name)."""
        return self.write(_with_extension(path, ".obj"))


def _with_extension(path: PathLike, ext: str) -> str:
    p = _os.fspath(path)
    if not p.lower().endswith(ext):
        raise OptionsError(f"{p}: expected a {ext} file name")
    return p


def triangulate(
    xyz: _typing.Any,
    *,
    duplicates: str = "first",
    breaklines: _typing.Sequence[_typing.Any] | _np.ndarray | None = None,
) -> Tin:
    """Exact Delaunay triangulation of the points ``xyz`` (an ``(n, 3)`` array; ``z`` is
    carried along). The result depends only on the set of distinct (x, y) positions, never on
    their order (a documented tie rule decides cocircular points).

    ``duplicates``: which point survives among exact (x, y) duplicates (``"first"``,
    ``"last"``, ``"lowest"``, ``"highest"`` z).

    ``breaklines``: a constrained triangulation. Either an ``(m, 2)`` integer array of
    segments (rows of ``xyz``), or a list of polylines, each a 1-D sequence of row indices of
    ``xyz`` or an ``(k, 3)`` float array of new vertices (appended after the points:
    ``input_index`` then counts them from ``len(xyz)`` on). Segments must not cross each other
    (a crossing one is left out and counted in :attr:`Tin.crossing_skipped`).

    A float64 C-contiguous array is used without a copy; the GIL is released while it works.
    Raises :class:`NoTriangleError` for fewer than 3 distinct points or all collinear,
    :class:`InputError` for a NaN/infinite or out-of-range coordinate (``.index`` names it).
    """
    pts = _points(xyz, 3, "xyz")
    segments = None
    if breaklines is not None:
        pts, segments = _segments(pts, breaklines)
    return Tin(_native.triangulate(pts, duplicates, segments))


def _segments(pts: _np.ndarray, breaklines: _typing.Any) -> tuple[_np.ndarray, _np.ndarray | None]:
    n = pts.shape[0]
    if isinstance(breaklines, _np.ndarray) and breaklines.ndim == 2 and breaklines.shape[1] == 2:
        seg = breaklines
        if not _np.issubdtype(seg.dtype, _np.integer):
            raise OptionsError("breaklines as an (m, 2) array must hold integer point indices")
        if len(seg) and (seg.min() < 0 or seg.max() >= n):
            raise OptionsError(f"a breakline segment refers to a point beyond the {n} given")
        return pts, _np.ascontiguousarray(seg, dtype=_np.uint32)
    extra: list[_np.ndarray] = []
    segs: list[_np.ndarray] = []
    total = n
    for k, line in enumerate(breaklines):
        a = _np.asarray(line)
        if a.ndim == 1 and _np.issubdtype(a.dtype, _np.integer):
            idx = a.astype(_np.int64)
            if len(idx) and (idx.min() < 0 or idx.max() >= n):
                raise OptionsError(f"breakline {k} refers to a point beyond the {n} given")
        elif a.ndim == 2 and a.shape[1] == 3:
            extra.append(_np.asarray(a, dtype=_np.float64))
            idx = _np.arange(total, total + len(a), dtype=_np.int64)
            total += len(a)
        else:
            raise OptionsError(
                f"breakline {k}: expected point indices (1-D integers) or (k, 3) coordinates, "
                f"not shape {a.shape}"
            )
        if len(idx) >= 2:
            segs.append(_np.stack([idx[:-1], idx[1:]], axis=1))
    if extra:
        pts = _np.ascontiguousarray(_np.concatenate([pts, *extra]))
    if not segs:
        return pts, None
    return pts, _np.ascontiguousarray(_np.concatenate(segs), dtype=_np.uint32)


# ---- files -------------------------------------------------------------------------------

_INPUT_DEFAULTS: dict[str, _typing.Any] = {
    "classes": None,
    "returns": "all",
    "keep_withheld": False,
    "bbox": None,
    "duplicates": "first",
    "breaklines": (),
    "trim_boundary": None,
    "holes": None,
    "max_edge": None,
    "mem": None,
    "tmp_dir": None,
    "engine": "auto",
    "threads": 0,
    "tile": None,
    "crs": None,
    "progress": False,
}


def _files(files: Files) -> list[str]:
    if isinstance(files, (str, _os.PathLike)):
        return [_os.fspath(files)]
    out = [_os.fspath(f) for f in files]
    if not out:
        raise OptionsError("no input files given")
    return out


def _mem(mem: int | str | None) -> int:
    """The memory budget in bytes, parsed and checked as ``--mem`` is (``0`` is refused)."""
    if mem is None:
        return _native.default_mem()
    text = mem if isinstance(mem, str) else str(_whole(mem, "mem"))
    return _named("mem", mem, _native.parse_size, text)


# The ground filter's parameters (:func:`ground`'s), taken with ``ground=True``.
_GROUND_KEYS = (
    "preset",
    "step",
    "max_distance",
    "max_angle",
    "low_noise",
    "offset",
    "densify_cell",
    "mirror",
    "reset",
)


def _ground_opts(ground: bool, options: dict[str, _typing.Any]) -> dict[str, _typing.Any] | None:
    """``ground=True`` and the filter's parameters (popped from ``options``) for the native
    module, as the command line's ``--ground`` and its options; ``None`` without."""
    given = {k: options.pop(k) for k in _GROUND_KEYS if k in options}
    if not ground:
        if given:
            raise OptionsError(
                f"the ground filter's parameters ({', '.join(sorted(given))}) apply with ground=True"
            )
        return None
    from ._ground import _params

    return _params(given.pop("preset", None), given)


def _opts(files: Files, options: dict[str, _typing.Any]) -> dict[str, _typing.Any]:
    options = dict(options)
    ground = _ground_opts(bool(options.pop("ground", False)), options)
    unknown = set(options) - set(_INPUT_DEFAULTS)
    if unknown:
        raise TypeError(f"unknown option(s): {', '.join(sorted(unknown))}")
    o = {**_INPUT_DEFAULTS, **options}
    o["ground"] = ground
    o["files"] = _files(files)
    o["mem"] = _mem(o["mem"])
    o["breaklines"] = [_os.fspath(p) for p in o["breaklines"]]
    for k in ("trim_boundary", "holes", "tmp_dir"):
        if o[k] is not None:
            o[k] = _os.fspath(o[k])
    o["classes"] = _classes(o["classes"])
    o["threads"] = _whole(o["threads"], "threads")
    if o["bbox"] is not None:
        o["bbox"] = [float(v) for v in o["bbox"]]
    return o


def _raster(
    format: str | None, compress: str | None, predictor: str | None, bigtiff: bool
) -> dict[str, _typing.Any]:
    return {"format": format, "compress": compress, "predictor": predictor, "bigtiff": bool(bigtiff)}


def dem(
    files: Files,
    out: PathLike,
    *,
    cell: float = 1.0,
    align: str = "edges",
    snap: bool = False,
    nodata: float = -9999.0,
    format: str | None = None,
    compress: str | None = None,
    predictor: str | None = None,
    bigtiff: bool = False,
    contours: PathLike | None = None,
    interval: float = 1.0,
    base: float = 0.0,
    max_cells: int = 1 << 30,
    **options: _typing.Any,
) -> dict[str, _typing.Any]:
    """``sweeptin dem``: a DEM raster (``.tif`` float32 GeoTIFF or ``.asc``) of the TIN of the
    files, by linear interpolation at cell centres, streaming in bounded memory; optionally
    contour lines (``contours=`` a ``.geojson`` path) from the same pass. With ``bbox=`` the
    raster covers the cells whose centres lie in ``[xmin, xmax) × (ymin, ymax]``.

    ``align="edges"`` (default): cell edges on multiples of ``cell`` (GDAL's ``-tap``,
    LAStools, lasR: a 1 km tile at 1 m is 1000 × 1000 cells); ``"centres"``: cell centres on
    multiples (IGN's LiDAR HD lattice). ``format``: ``"tif"``, ``"cog"`` (Cloud Optimized
    GeoTIFF) or ``"asc"`` (default: by the extension); ``compress`` (``"deflate"``,
    ``"zstd"``, ``"lzw"``, ``"none"``), ``predictor`` (``"float"``, ``"horizontal"``,
    ``"none"``) and ``bigtiff`` as the command line's ``--compress``, ``--predictor`` and
    ``--bigtiff``. ``max_cells`` as ``--max-cells``: a raster of more cells is refused before
    any work (from ``bbox`` or the LAS/LAZ headers), and so is one whose rows do not fit in a
    quarter of ``mem``.

    ``ground=True`` triangulates the ground found on the fly, as the command line's
    ``--ground`` (the same bytes): the points classified by :func:`ground`'s filter (its
    parameters as keywords: ``preset``, ``step``, ``max_distance``, …; the files' own classes
    ignored), class 2 kept unless ``classes`` says otherwise. So do :func:`contours`,
    :func:`volume`, :func:`tin` and :func:`stream_triangles`; the summary's ``run["ground"]``
    is what the filter found (``sweeptin ground --json``'s summary).

    Returns the run's summary: ``{"run": {...}, "products": {"dem": {...}, ...}}``, the same
    fields as the command line's ``--json``."""
    o = _opts(files, options)
    d = {
        "out": _os.fspath(out),
        "cell": float(cell),
        "nodata": float(nodata),
        "snap": bool(snap),
        "align": align,
        **_raster(format, compress, predictor, bigtiff),
        "max_cells": _whole(max_cells, "max_cells"),
    }
    c = None if contours is None else (_os.fspath(contours), float(interval), float(base))
    return _json.loads(_native.run_products(o, dem=d, contours=c))


def contours(
    files: Files,
    out: PathLike,
    *,
    interval: float = 1.0,
    base: float = 0.0,
    **options: _typing.Any,
) -> dict[str, _typing.Any]:
    """``sweeptin contours``: contour lines at ``base + k × interval`` as GeoJSON, stitched
    into polylines, streaming in bounded memory. Returns the run's summary."""
    o = _opts(files, options)
    c = (_os.fspath(out), float(interval), float(base))
    return _json.loads(_native.run_products(o, contours=c))


def volume(
    files: Files,
    *,
    plane: float,
    boundary: PathLike | None = None,
    **options: _typing.Any,
) -> dict[str, _typing.Any]:
    """``sweeptin volume --plane``: cut and fill volumes and areas of the TIN against the plane
    ``z = plane``, within an optional GeoJSON polygon. Returns the run's summary; the volumes
    are ``result["products"]["volume"]`` (``cut_volume``, ``fill_volume``, ``net_volume``,
    ``cut_area``, ``fill_area``, ``area``)."""
    o = _opts(files, options)
    b = None if boundary is None else _os.fspath(boundary)
    return _json.loads(_native.run_products(o, volume=(float(plane), b)))


def tin(files: Files, out: PathLike, **options: _typing.Any) -> dict[str, _typing.Any]:
    """``sweeptin tin``: the Delaunay TIN of the files written as ``.ply``, ``.obj``, ``.xml``
    (LandXML) or ``.stin``, streaming in bounded memory. Returns the run's summary."""
    o = _opts(files, options)
    return _json.loads(_native.run_tin(o, _os.fspath(out)))


class _Stream:
    """The iterator of :func:`stream_triangles`."""

    __slots__ = ("_it",)

    def __init__(self, it: _typing.Any) -> None:
        self._it = it

    def __iter__(self) -> "_Stream":
        return self

    def __next__(self) -> _np.ndarray:
        return next(self._it)

    @property
    def summary(self) -> dict[str, _typing.Any] | None:
        """The run's summary once the iterator is exhausted (else ``None``)."""
        s = self._it.summary_json()
        return None if s is None else _json.loads(s)


def stream_triangles(
    files: Files, chunk: int | None = None, **options: _typing.Any
) -> _typing.Iterator[_np.ndarray]:
    """Iterates over the final triangles of a streaming run over the files, in chunks: float64
    arrays of shape ``(k, 3, 3)`` (``k <= chunk`` triangles, three ``[x, y, z]`` corners each,
    counter-clockwise), as the sweep releases them (roughly south to north). Memory stays
    bounded (at most two chunks wait in the pipe). Stopping early stops the run. The returned
    iterator has ``.summary`` once exhausted.

    ``chunk``: most triangles a chunk holds (72 bytes each), at most what a quarter of ``mem``
    holds (:class:`OptionsError` beyond, before any work); default 1,000,000, or that many
    when fewer."""
    o = _opts(files, options)
    n = None if chunk is None else _whole(chunk, "chunk")
    return _Stream(_native.stream_triangles(o, n))


# ---- plans -------------------------------------------------------------------------------


class Plan:
    """A tile plan (``DIR/plan.json``): ``len(plan)`` tasks, run in any order, anywhere that
    sees the files, then merged. Picklable (it is its path), so it can be sent to workers."""

    __slots__ = ("path",)

    def __init__(self, path: PathLike) -> None:
        self.path = _absolute(_os.fspath(path))

    def __fspath__(self) -> str:
        return self.path

    def __len__(self) -> int:
        return int(_native.task_count(self.path))

    def __repr__(self) -> str:
        return f"sweeptin.Plan({self.path!r})"

    def __reduce__(self) -> tuple[_typing.Any, ...]:
        return (Plan, (self.path,))

    @property
    def tasks(self) -> range:
        """The task indices ``0 .. len(plan) - 1``."""
        return range(len(self))


def _absolute(path: str) -> str:
    """A local path made absolute; a URL (``s3://…``, ``https://…``) as it is."""
    return path if _re.match(r"[A-Za-z][A-Za-z0-9+.-]*://", path) else _os.path.abspath(path)


def _plan_path(p: Plan | PathLike) -> str:
    path = _os.fspath(p)
    return _os.path.join(path, "plan.json") if _os.path.isdir(path) else path


def plan(
    product: str,
    files: Files,
    dir: PathLike,
    *,
    tile: float,
    buffer: float | None = None,
    cell: float = 1.0,
    align: str = "edges",
    nodata: float = -9999.0,
    format: str | None = None,
    compress: str | None = None,
    predictor: str | None = None,
    bigtiff: bool = False,
    contours: PathLike | None = None,
    interval: float = 1.0,
    base: float = 0.0,
    plane: float | None = None,
    boundary: PathLike | None = None,
    ground: bool = False,
    classes: _typing.Sequence[int] | int | str | None = None,
    returns: str = "all",
    keep_withheld: bool = False,
    duplicates: str = "first",
    max_edge: float | None = None,
    breaklines: _typing.Sequence[PathLike] = (),
    trim_boundary: PathLike | None = None,
    holes: PathLike | None = None,
    crs: str | None = None,
    mem: int | str | None = None,
    tmp_dir: PathLike | None = None,
    **ground_params: _typing.Any,
) -> Plan:
    """``sweeptin plan``: cuts a ``"dem"``, ``"contours"``, ``"volume"`` or ``"tin"`` job over
    LAS/LAZ files into tiles of side ``tile`` (a multiple of ``cell``), one task each, and writes
    ``DIR/plan.json`` (from the files' headers only). ``buffer``: the first buffer of every
    task (default a tenth of the tile; a task widens it by itself when needed, so this never
    changes the result). A DEM plan may also make ``contours`` (the path ``merge`` writes).
    ``align``, ``format`` (``"tif"`` or ``"cog"``: the mosaic's; the tasks write plain GeoTIFF
    tiles), ``compress``, ``predictor`` and ``bigtiff`` as in :func:`dem`. ``files`` may name
    ``.vpc`` virtual point clouds, ``@list.txt`` files and globs; the plan stores every file by
    absolute path. Run the tasks with :func:`run_task` (any order, any machine: ``sweeptin
    run`` too) and join them with :func:`merge`; the result equals one run over all the
    files (a ``"tin"`` plan's merge writes one mesh, ``.ply``, ``.obj``, ``.xml`` or ``.stin``
    by its extension, with the triangles of one run). ``breaklines``, ``trim_boundary`` and
    ``holes`` go into every task when every vertex has a z (3-D lines and rings; the plan
    records each file with its size and SHA-256, and a task refuses one that changed); lines
    without z raise :class:`OptionsError` naming the first such vertex. ``ground=True`` (with
    :func:`ground`'s parameters as keywords) plans on the ground found on the fly, as
    ``sweeptin plan … --ground``: every task classifies the ground of its area as one run over
    all the files would, so the merge is one ``dem(..., ground=True)``'s. ``"ground"`` tiles
    the classification itself, as ``sweeptin plan ground`` (``ground=True`` implied, the
    filter's parameters and ``reset`` as keywords): every task writes the points its tile owns
    with one :func:`ground` run's classes, and :func:`merge` writes a ``.vpc`` of the tiles or
    one ``.laz``/``.las`` file of every point (in tile order, not the inputs' order)."""
    rest = dict(ground_params)
    if product == "ground":
        if classes is not None or buffer is not None:
            raise OptionsError("a ground plan keeps every point and has no buffer: leave "
                               "classes= and buffer= out")
        ground = True
    g = _ground_opts(bool(ground), rest)
    if rest:
        raise TypeError(f"unknown option(s): {', '.join(sorted(rest))}")
    job = {
        "product": product,
        "cell": float(cell),
        "align": align,
        "nodata": float(nodata),
        **_raster(format, compress, predictor, bigtiff),
        "contours": None if contours is None else _absolute(_os.fspath(contours)),
        "interval": float(interval),
        "base": float(base),
        "plane": None if plane is None else float(plane),
        "boundary": None if boundary is None else _os.fspath(boundary),
        "classes": _classes(classes),
        "returns": returns,
        "keep_withheld": bool(keep_withheld),
        "duplicates": duplicates,
        "max_edge": max_edge,
        "breaklines": [_os.fspath(p) for p in breaklines],
        "trim_boundary": None if trim_boundary is None else _os.fspath(trim_boundary),
        "holes": None if holes is None else _os.fspath(holes),
        "crs": crs,
        "mem": _mem(mem),
        "tmp_dir": None if tmp_dir is None else _os.fspath(tmp_dir),
        "ground": g,
    }
    names = _files(files)
    args = [product, *[_absolute(f) for f in names], "--tile", repr(float(tile))]
    if product == "dem":
        args += ["--cell", repr(float(cell)), "--align", align]
        if format is not None:
            args += ["--format", format]
    if job["classes"] is not None:
        args += ["--class", ",".join(str(c) for c in job["classes"])]
    if g is not None and product != "ground":
        args += ["--ground"]
    for flag, paths in (("--breaklines", job["breaklines"]), ("--trim-boundary", [trim_boundary]),
                        ("--holes", [holes])):
        args += [a for p in paths if p is not None for a in (flag, _absolute(_os.fspath(p)))]
    path = _native.make_plan(names, _os.fspath(dir), float(tile), buffer, job, args)
    return Plan(path)


def run_task(
    plan: Plan | PathLike,
    i: int,
    *,
    threads: int = 0,
    resume: bool = False,
    progress: bool = False,
) -> dict[str, _typing.Any]:
    """``sweeptin run --task i``: runs task ``i`` of the plan (its outputs under
    ``DIR/tiles/``, then its record); with ``resume`` a finished task is skipped. ``threads``:
    the task's worker threads (0: every core). Returns the task's record (status ``"done"``,
    or ``"empty"`` when its tile holds no point after the filters)."""
    task = _whole(i, "i")
    return _json.loads(
        _native.run_task(_plan_path(plan), task, _whole(threads, "threads"), bool(resume), bool(progress))
    )


def merge(
    plan: Plan | PathLike,
    out: PathLike | None = None,
    *,
    contours: PathLike | None = None,
    hillshade: PathLike | None = None,
    format: str | None = None,
    compress: str | None = None,
    predictor: str | None = None,
    bigtiff: bool = False,
    extent: str = "data",
    mem: int | str | None = None,
) -> dict[str, _typing.Any]:
    """``sweeptin merge``: joins the finished tasks: the DEM mosaic ``out`` (``.vrt`` over the
    tiles or one ``.tif``, a GeoTIFF or COG as the plan's ``format`` says unless ``format``,
    ``compress``, ``predictor`` or ``bigtiff`` are given here) with the DEM's contours
    (``contours=``, default: the path the plan was given) and a ``hillshade`` of a ``.tif``
    mosaic (``.png`` with a world file, or an 8-bit ``.tif``); the stitched contours ``out``
    (``.geojson``); the TIN ``out`` (``.ply``, ``.obj``, ``.xml`` or ``.stin``, each vertex
    once); or the summed volumes (no ``out``). Returns the summary
    (``dem``/``contours``/``hillshade``/``volume``/``tin``, ``tasks``, ``empty_tasks``,
    ``max_buffer``, ``warnings``; a ground plan's ``points``: ``out`` a ``.vpc`` of its
    tiles or one ``.laz``/``.las``). The mosaic's cells are those one run writes
    (``extent="data"``: the same header and cells as ``dem`` over the plan's files and filters),
    or the whole tiles (``extent="tiles"``). ``mem`` is the merge's memory budget, as ``--mem``
    (at least 16M)."""
    opts = {
        "out": None if out is None else _os.fspath(out),
        "extent": extent,
        "mem": _mem(mem),
        "contours": None if contours is None else _os.fspath(contours),
        "hillshade": None if hillshade is None else _os.fspath(hillshade),
        **_raster(format, compress, predictor, bigtiff),
    }
    return _json.loads(_native.merge(_plan_path(plan), opts))


from ._ground import ground, height  # noqa: E402  (uses the helpers above)
