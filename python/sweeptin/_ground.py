"""Ground classification and heights above ground (``sweeptin ground``, ``sweeptin height``):
on numpy arrays in memory, or on LAS/LAZ/COPC files in bounded memory. Imported into
:mod:`sweeptin`; see :func:`sweeptin.ground` and :func:`sweeptin.height`."""

from __future__ import annotations

import json as _json
import os as _os
import typing as _typing

import numpy as _np

from . import _sweeptin as _native
from ._errors import OptionsError

PRESETS = ("wilderness", "nature", "town", "city", "metro", "forest", "mountains")


def _params(preset: str | None, options: dict[str, _typing.Any]) -> dict[str, _typing.Any]:
    """The filter's parameters for the native module: ``None`` keeps the preset's value."""
    known = {"step", "max_distance", "max_angle", "low_noise", "offset", "densify_cell", "mirror", "reset"}
    unknown = set(options) - known
    if unknown:
        raise TypeError(f"unknown option(s): {', '.join(sorted(unknown))}")
    p: dict[str, _typing.Any] = {"preset": preset, "mirror": True, "reset": False}
    for k in ("step", "max_distance", "max_angle", "low_noise", "offset", "densify_cell"):
        v = options.get(k)
        p[k] = None if v is None else float(v)
    p["mirror"] = bool(options.get("mirror", True))
    p["reset"] = bool(options.get("reset", False))
    return p


def _is_arrays(x: _typing.Any, y: _typing.Any) -> bool:
    return y is not None or isinstance(x, _np.ndarray)


def _xyz(x: _typing.Any, y: _typing.Any, z: _typing.Any) -> _np.ndarray:
    """An ``(n, 3)`` C-contiguous float64 array from ``x, y, z`` or from one ``(n, 3)`` array."""
    if y is None and z is None:
        a = _np.ascontiguousarray(x, dtype=_np.float64)
        if a.ndim != 2 or a.shape[1] != 3:
            raise OptionsError(f"give x, y, z arrays or one (n, 3) array, not shape {a.shape}")
        return a
    if y is None or z is None:
        raise OptionsError("give x, y and z (three arrays of the same length)")
    cols = [_np.asarray(v, dtype=_np.float64) for v in (x, y, z)]
    if any(c.ndim != 1 for c in cols) or len({len(c) for c in cols}) != 1:
        raise OptionsError("x, y and z must be 1-D arrays of the same length")
    return _np.ascontiguousarray(_np.stack(cols, axis=1))


def _column(v: _typing.Any, n: int, dtype: _typing.Any, name: str, default: _typing.Any) -> _np.ndarray:
    if v is None:
        return _np.full(n, default, dtype=dtype)
    a = _np.ascontiguousarray(v, dtype=dtype)
    if a.shape != (n,):
        raise OptionsError(f"{name} must have one value per point ({n}), not shape {a.shape}")
    return a


def _outputs(files: list[str], output: _typing.Any, odir: _typing.Any, what: str) -> list[str]:
    if (output is None) == (odir is None):
        raise OptionsError(f"{what}: give output= (one input) or odir= (each input there under its own name)")
    if output is not None:
        if len(files) != 1:
            raise OptionsError(f"{what}: output= names one file for {len(files)} inputs: give odir=")
        return [_os.fspath(output)]
    d = _os.fspath(odir)
    if not _os.path.isdir(d):
        raise OptionsError(f"odir={d}: not a directory (create it first)")
    out = []
    for f in files:
        name = _os.path.basename(f)
        if name.lower().endswith(".copc.laz"):
            name = name[: -len(".copc.laz")] + ".laz"
        out.append(_os.path.join(d, name))
    return out


def ground(
    x: _typing.Any,
    y: _typing.Any = None,
    z: _typing.Any = None,
    *,
    output: _typing.Any = None,
    odir: _typing.Any = None,
    classes: _typing.Any = None,
    withheld: _typing.Any = None,
    preset: str | None = None,
    mem: int | str | None = None,
    tmp_dir: _typing.Any = None,
    **params: _typing.Any,
) -> _typing.Any:
    """The ground filter of ``sweeptin ground`` (progressive TIN densification, docs/GROUND.md).

    On arrays, ``ground(x, y, z)`` (or ``ground(xyz)`` with an ``(n, 3)`` array) returns the
    class of every point as a ``uint8`` array: 2 ground, 7 low noise, the others their own
    (a point of class 2 that is not ground 1; all 1 with ``reset``). ``classes`` and ``withheld`` give the
    points' own classes (default 0) and withheld flags (default ``False``); withheld points and
    noise (7, 18) take no part and keep their class. The classes are the same as the command
    line writes for the same points in the same order.

    On files, ``ground(files, output=...)`` (one input) or ``ground(files, odir=...)`` writes
    every input with its new classes, every other attribute kept (the files are classified
    together), and returns the summary as ``sweeptin ground --json`` has it. An ``output``
    named ``.copc.laz`` is a COPC file of the same points in octree order, as on the command
    line (docs/GROUND.md).

    Parameters (keyword): ``preset`` (one of ``"wilderness"``, ``"nature"``, ``"town"``,
    ``"city"``, ``"metro"``, ``"forest"``, ``"mountains"``), ``step``, ``max_distance``,
    ``max_angle``, ``low_noise``, ``offset``, ``densify_cell`` (each over the preset's), ``mirror`` (default
    ``True``), ``reset`` (the other points become class 1), ``mem``, ``tmp_dir`` (files).
    """
    from . import _files, _mem

    p = _params(preset, params)
    budget = _mem(mem)
    if _is_arrays(x, y):
        if output is not None or odir is not None:
            raise OptionsError("output=/odir= are for files: on arrays ground() returns the classes")
        xyz = _xyz(x, y, z)
        n = xyz.shape[0]
        c = _column(classes, n, _np.uint8, "classes", 0)
        w = _column(withheld, n, _np.bool_, "withheld", False)
        return _native.ground_points(xyz, c, w, p, budget)
    if classes is not None or withheld is not None:
        raise OptionsError("classes=/withheld= are for arrays: files carry their own")
    files = _files(x)
    outs = _outputs(files, output, odir, "ground")
    tmp = None if tmp_dir is None else _os.fspath(tmp_dir)
    return _json.loads(_native.ground_files(files, outs, p, budget, tmp))


def height(
    x: _typing.Any,
    y: _typing.Any = None,
    z: _typing.Any = None,
    *,
    output: _typing.Any = None,
    odir: _typing.Any = None,
    ground: bool = False,
    ground_class: _typing.Any = 2,
    replace_z: bool = False,
    classes: _typing.Any = None,
    withheld: _typing.Any = None,
    preset: str | None = None,
    mem: int | str | None = None,
    threads: int = 0,
    tmp_dir: _typing.Any = None,
    **params: _typing.Any,
) -> _typing.Any:
    """Height above the ground TIN, as ``sweeptin height``.

    The ground is the points of ``ground_class`` (default 2), or with ``ground=True`` the
    points the ground filter finds (:func:`ground`'s parameters: ``preset``, ``step``, …).

    On arrays, ``height(x, y, z, classes=...)`` (or ``ground=True``) returns ``z`` minus the
    ground TIN's height at every point as a float64 array, NaN outside the ground's hull (the
    command line's heights to within rounding in the last bits: :meth:`Tin.interpolate`).

    On files, ``height(files, output=...)`` or ``odir=...`` writes each input with a
    ``HeightAboveGround`` attribute (or its z replaced with ``replace_z=True``) and returns the
    summary.
    """
    from . import _classes, _files, _mem, _whole, triangulate

    if not ground and (preset is not None or params):
        raise OptionsError("the ground filter's parameters apply with ground=True")
    p = _params(preset, params) if ground else None
    budget = _mem(mem)
    wanted = _classes(ground_class) or [2]
    if _is_arrays(x, y):
        xyz = _xyz(x, y, z)
        n = xyz.shape[0]
        if ground:
            c = ground_fn(xyz, classes=classes, withheld=withheld, preset=preset, mem=budget, **params)
            is_ground = c == 2
        else:
            if classes is None:
                raise OptionsError("give classes= (the points' classes), or ground=True")
            c = _column(classes, n, _np.uint8, "classes", 0)
            is_ground = _np.isin(c, wanted)
            if withheld is not None:
                is_ground &= ~_column(withheld, n, _np.bool_, "withheld", False)
        tin = triangulate(xyz[is_ground])
        return xyz[:, 2] - tin.interpolate(xyz[:, :2])
    files = _files(x)
    outs = _outputs(files, output, odir, "height")
    tmp = None if tmp_dir is None else _os.fspath(tmp_dir)
    return _json.loads(
        _native.height_files(files, outs, p, wanted, bool(replace_z), budget, _whole(threads, "threads"), tmp)
    )


ground_fn = ground
