# Type stubs of the native module (python/src/*.rs). Users call the wrappers in
# sweeptin/__init__.py, which carry the documentation.
from os import PathLike
from typing import Any, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, PathLike[str]]

class Tin:
    @property
    def vertices(self) -> npt.NDArray[np.float64]: ...
    @property
    def triangles(self) -> npt.NDArray[np.uint32]: ...
    @property
    def input_index(self) -> npt.NDArray[np.uint32]: ...
    @property
    def duplicates(self) -> int: ...
    @property
    def crossing_skipped(self) -> int: ...
    def interpolate(self, xy: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...
    def rasterize(
        self,
        cell: float,
        bbox: Optional[Sequence[float]] = None,
        align: str = "edges",
        nodata: float = ...,
        snap: bool = False,
        max_cells: int = ...,
    ) -> tuple[npt.NDArray[np.float32], tuple[float, float, float, float, float, float]]: ...
    def contours_geojson(self, interval: float = 1.0, base: float = 0.0) -> str: ...
    def write(self, path: _Path, crs: Optional[str] = None) -> tuple[int, int, int]: ...

class TriangleStream:
    def __iter__(self) -> TriangleStream: ...
    def __next__(self) -> npt.NDArray[np.float64]: ...
    def summary_json(self) -> Optional[str]: ...

def triangulate(
    xyz: npt.NDArray[np.float64],
    duplicates: str = "first",
    segments: Optional[npt.NDArray[np.uint32]] = None,
) -> Tin: ...
def run_products(
    opts: dict[str, Any],
    dem: Optional[dict[str, Any]] = None,
    contours: Optional[tuple[str, float, float]] = None,
    volume: Optional[tuple[float, Optional[str]]] = None,
) -> str: ...
def run_tin(opts: dict[str, Any], out: _Path) -> str: ...
def stream_triangles(opts: dict[str, Any], chunk: Optional[int] = None) -> TriangleStream: ...
def parse_size(s: str) -> int: ...
def parse_classes(s: str) -> list[int]: ...
def default_mem() -> int: ...
def make_plan(
    files: Sequence[_Path],
    dir: _Path,
    tile: float,
    buffer: Optional[float],
    job: dict[str, Any],
    args: Sequence[str],
) -> str: ...
def task_count(path: _Path) -> int: ...
def run_task(
    path: _Path, i: int, threads: int = 0, resume: bool = False, progress: bool = False
) -> str: ...
def merge(path: _Path, opts: dict[str, Any]) -> str: ...
def ground_points(
    xyz: npt.NDArray[np.float64],
    classes: npt.NDArray[np.uint8],
    withheld: npt.NDArray[np.bool_],
    params: dict[str, Any],
    mem: int,
) -> npt.NDArray[np.uint8]: ...
def ground_files(
    files: Sequence[_Path],
    outputs: Sequence[_Path],
    params: dict[str, Any],
    mem: int,
    tmp_dir: Optional[_Path] = None,
) -> str: ...
def height_files(
    files: Sequence[_Path],
    outputs: Sequence[_Path],
    params: Optional[dict[str, Any]],
    ground_class: Sequence[int],
    replace_z: bool,
    mem: int,
    threads: int,
    tmp_dir: Optional[_Path] = None,
) -> str: ...
