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
    """A file of the real data (../shared/data beside the repository, or $SWEEPTIN_DATA)."""
    for base in (os.environ.get("SWEEPTIN_DATA"), REPO.parent / "shared" / "data", "/work/shared/data"):
        if base and (Path(base) / rel).exists():
            return Path(base) / rel
    missing(f"test data {rel}")
    raise AssertionError("unreachable")


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


@pytest.fixture(scope="session")
def small():
    """startinpy's demo file (39,233 points, EPSG:7415) as a path and its xyz array."""
    laspy = pytest.importorskip("laspy") if not in_ci() else __import__("laspy")
    import numpy as np

    p = data("lidar/startinpy_small.laz")
    las = laspy.read(p)
    return p, np.column_stack([las.x, las.y, las.z])
