"""Where the real data, the command-line binary and the Rust example are, for the tests.

A test that needs something missing must not pass silently: under CI=true it fails; locally it
is skipped with the reason (as tests/support/data.rs does for the Rust tests).
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def in_ci() -> bool:
    return os.environ.get("CI", "") in ("true", "1")


def missing(what: str) -> None:
    if in_ci():
        pytest.fail(f"{what} is required under CI=true but missing")
    pytest.skip(f"{what} not found")


def data(rel: str) -> Path:
    """A file of the real data committed in tests/data (docs/DATA.md), as tests/support/data.rs
    finds it for the Rust tests."""
    p = REPO / "tests" / "data" / rel
    if not p.exists():
        missing(f"test data {p}")
    return p


def built(rel: str, env: str) -> Path:
    """A program built by `cargo test`/`cargo build` under target/ (or the path in $env)."""
    if os.environ.get(env):
        return Path(os.environ[env])
    for profile in ("debug", "release"):
        p = REPO / "target" / profile / rel
        if p.exists():
            return p
    missing(f"{rel} (run `cargo build` first, or set {env})")
    raise AssertionError("unreachable")


@pytest.fixture(scope="session")
def cli():
    """Runs the `sweeptin` binary; returns its CompletedProcess (stdout text)."""
    exe = built("sweeptin", "SWEEPTIN_BIN")

    def run(*args: object) -> subprocess.CompletedProcess[str]:
        r = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True)
        assert r.returncode == 0, f"sweeptin {args}: {r.stderr}"
        return r

    return run


@pytest.fixture(scope="session")
def rust_triangulate():
    """The Rust API's `triangulate` (dev/triangulate_raw.rs) on an (n, 3) array."""
    exe = built("examples/triangulate_raw", "SWEEPTIN_TRIANGULATE_RAW")

    def run(xyz, tmp: Path, policy: str = "first"):
        import numpy as np

        pts = tmp / "points.f64"
        np.ascontiguousarray(xyz, dtype="<f8").tofile(pts)
        subprocess.run([str(exe), str(pts), str(tmp / "out"), policy], check=True)
        v = np.fromfile(tmp / "out.vertices", dtype="<f8").reshape(-1, 3)
        t = np.fromfile(tmp / "out.triangles", dtype="<u4").reshape(-1, 3)
        i = np.fromfile(tmp / "out.input_index", dtype="<u4")
        return v, t, i

    return run


def world(las):
    """The points of a laspy ``LasData`` as the doubles sweeptin reads from the file: when
    ``scale = S / 10^k`` and ``offset = O / 10^k`` (short decimals, checked by round trip), the
    double nearest the decimal value, ``(S × N + O) / 10^k`` (one correctly rounded division;
    src/input/las/world.rs), else ``offset + scale × N``. laspy's ``las.x`` is the latter, which
    rounds twice and can be one unit in the last place away, so comparing outputs of a file
    with those of laspy's arrays needs this."""
    import numpy as np

    axes = []
    for raw, scale, offset in zip((las.X, las.Y, las.Z), las.header.scales, las.header.offsets):
        n = np.asarray(raw, dtype=np.int64)
        scale, offset, p = float(scale), float(offset), 1.0
        for _ in range(16):
            s, o = float(np.round(scale * p)), float(np.round(offset * p))
            if 1 <= s <= 2**21 and abs(o) < 2**52 and s / p == scale and o / p == offset:
                axes.append((n * int(s) + int(o)).astype(np.float64) / p)
                break
            p *= 10.0
        else:
            axes.append(offset + scale * n.astype(np.float64))
    return np.column_stack(axes) + 0.0


@pytest.fixture(scope="session")
def small():
    """startinpy's demo file (39,233 points, EPSG:7415) as a path and its xyz array (the
    doubles sweeptin reads from the file: :func:`world`)."""
    laspy = pytest.importorskip("laspy") if not in_ci() else __import__("laspy")
    import numpy as np

    p = data("lidar/startinpy_small.laz")
    las = laspy.read(p)
    xyz = world(las)
    # The two roundings differ from the decimal value at some points, never by more than an ulp.
    assert np.allclose(xyz, np.column_stack([las.x, las.y, las.z]), rtol=1e-15, atol=0)
    return p, xyz
