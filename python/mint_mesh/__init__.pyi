# Type stubs of mint_mesh: every call with the command line's options as
# keywords (`_` for `-`), so that editors complete them. `**options` takes
# any other long option of the command (see `mint <command> --help`).

import os
from typing import Any, Callable, Iterable, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

from ._errors import (
    BudgetError as BudgetError,
    CancelledError as CancelledError,
    InputError as InputError,
    MintError as MintError,
    MintIOError as MintIOError,
    MintWarning as MintWarning,
    UsageError as UsageError,
)

__version__: str

PathLike = Union[str, os.PathLike[str]]
Paths = Union[PathLike, Iterable[PathLike]]
# Called as progress(phase, done, total); total is 0 when unknown. Return
# False to stop the run (CancelledError); an exception raised stops it too.
Progress = Callable[[str, int, int], Optional[bool]]
Vertices = npt.ArrayLike  # (N, 3) float32 or float64
Faces = npt.ArrayLike  # (M, 3) int32, int64 or uint32
Colors = npt.ArrayLike  # (N, 3) or (N, 4) uint8
# (vertices, faces), or any object with .vertices and .faces (trimesh.Trimesh)
Mesh = Any
Size = Union[str, Tuple[int, int]]
Signs = Literal["auto", "orient", "union", "parity", "sheet"]
Axis = Literal["auto", "x", "y", "z"]
Deref = Literal["auto", "mmap", "sort"]
Op = Literal["union", "intersection", "difference"]
View = Literal["iso", "front", "right", "top", "back", "left", "bottom", "all"]

class MeshResult(tuple):
    """(vertices, faces) or (vertices, faces, colors), with .summary."""

    summary: dict
    @property
    def vertices(self) -> npt.NDArray[np.float64]: ...
    @property
    def faces(self) -> npt.NDArray[np.int64]: ...
    @property
    def colors(self) -> Optional[npt.NDArray[np.uint8]]: ...

def run(argv: Sequence[str], progress: Optional[Progress] = ...) -> Optional[dict]: ...
def read(path: PathLike) -> MeshResult: ...
def write(path: PathLike, vertices: Union[Vertices, Mesh], faces: Optional[Faces] = ..., colors: Optional[Colors] = ...) -> None: ...
def resample(
    vertices: Union[Vertices, Mesh],
    faces: Optional[Faces] = ...,
    *,
    colors: Optional[Colors] = ...,
    cells: Optional[float] = ...,
    cell_size: Optional[float] = ...,
    axis: Optional[Axis] = ...,
    signs: Optional[Signs] = ...,
    max_hole: Optional[int] = ...,
    close_all: bool = ...,
    double: bool = ...,
    no_color: bool = ...,
    mem: Optional[Union[str, int]] = ...,
    threads: Optional[int] = ...,
    tmp: Optional[PathLike] = ...,
    slab: Optional[int] = ...,
    deref: Optional[Deref] = ...,
    progress: Optional[Progress] = ...,
    **options: Any,
) -> MeshResult: ...
def decimate(
    vertices: Union[Vertices, Mesh],
    faces: Optional[Faces] = ...,
    *,
    target_faces: int,
    colors: Optional[Colors] = ...,
    route: Optional[Literal["auto", "direct", "resample"]] = ...,
    intermediate: Optional[int] = ...,
    error: Optional[float] = ...,
    error_samples: Optional[int] = ...,
    color_weight: Optional[float] = ...,
    no_color: bool = ...,
    mem: Optional[Union[str, int]] = ...,
    threads: Optional[int] = ...,
    tmp: Optional[PathLike] = ...,
    progress: Optional[Progress] = ...,
    **options: Any,
) -> MeshResult: ...
def simplify(
    vertices: Union[Vertices, Mesh],
    faces: Optional[Faces] = ...,
    *,
    target_faces: int,
    colors: Optional[Colors] = ...,
    error: Optional[float] = ...,
    error_samples: Optional[int] = ...,
    no_weld: bool = ...,
    double: bool = ...,
    color_weight: Optional[float] = ...,
    no_color: bool = ...,
    tmp: Optional[PathLike] = ...,
    progress: Optional[Progress] = ...,
    **options: Any,
) -> MeshResult: ...
def boolean(
    a: Mesh,
    b: Mesh,
    op: Op,
    *,
    cells: Optional[float] = ...,
    cell_size: Optional[float] = ...,
    signs: Optional[Signs] = ...,
    mem: Optional[Union[str, int]] = ...,
    threads: Optional[int] = ...,
    tmp: Optional[PathLike] = ...,
    progress: Optional[Progress] = ...,
    **options: Any,
) -> MeshResult: ...
def csg(
    scene: Union[dict, str],
    *,
    cells: Optional[float] = ...,
    cell_size: Optional[float] = ...,
    mem: Optional[Union[str, int]] = ...,
    threads: Optional[int] = ...,
    tmp: Optional[PathLike] = ...,
    progress: Optional[Progress] = ...,
    **options: Any,
) -> MeshResult: ...
def check(
    vertices: Union[Vertices, Mesh],
    faces: Optional[Faces] = ...,
    *,
    no_weld: bool = ...,
    self_intersections: bool = ...,
    mem: Optional[Union[str, int]] = ...,
    threads: Optional[int] = ...,
    tmp: Optional[PathLike] = ...,
    progress: Optional[Progress] = ...,
    **options: Any,
) -> dict: ...
def distance(a: Mesh, b: Mesh, *, samples: Optional[int] = ..., seed: Optional[int] = ..., tmp: Optional[PathLike] = ..., progress: Optional[Progress] = ..., **options: Any) -> dict: ...
def render(
    meshes: Union[Mesh, Sequence[Mesh]],
    *,
    size: Optional[Size] = ...,
    view: Optional[View] = ...,
    path: Optional[PathLike] = ...,
    up: Optional[Literal["x", "y", "z"]] = ...,
    color: Optional[Literal["vertex", "shading", "distance"]] = ...,
    wireframe: bool = ...,
    show_boundary: bool = ...,
    tmp: Optional[PathLike] = ...,
    progress: Optional[Progress] = ...,
    **options: Any,
) -> npt.NDArray[np.uint8]: ...
def generate(
    shape: Literal["sphere", "torus", "genus", "components", "scan"],
    *,
    faces: Optional[int] = ...,
    seed: Optional[int] = ...,
    genus: Optional[int] = ...,
    color: bool = ...,
    tmp: Optional[PathLike] = ...,
    **options: Any,
) -> MeshResult: ...
def resample_file(
    inputs: Paths,
    output: PathLike,
    *,
    cells: Optional[float] = ...,
    mem: Optional[Union[str, int]] = ...,
    work: Optional[PathLike] = ...,
    parts: Optional[int] = ...,
    slabs: Optional[int] = ...,
    cell_size: Optional[float] = ...,
    axis: Optional[Axis] = ...,
    signs: Optional[Signs] = ...,
    max_hole: Optional[int] = ...,
    close_all: bool = ...,
    ascii: bool = ...,
    double: bool = ...,
    no_color: bool = ...,
    threads: Optional[int] = ...,
    tmp: Optional[PathLike] = ...,
    slab: Optional[int] = ...,
    deref: Optional[Deref] = ...,
    preview: bool = ...,
    progress: Optional[Progress] = ...,
    **options: Any,
) -> dict: ...
def decimate_file(
    inputs: Paths,
    output: PathLike,
    *,
    target_faces: int,
    mem: Optional[Union[str, int]] = ...,
    route: Optional[Literal["auto", "direct", "resample"]] = ...,
    intermediate: Optional[int] = ...,
    error: Optional[float] = ...,
    error_samples: Optional[int] = ...,
    work: Optional[PathLike] = ...,
    threads: Optional[int] = ...,
    tmp: Optional[PathLike] = ...,
    no_color: bool = ...,
    color_weight: Optional[float] = ...,
    preview: bool = ...,
    progress: Optional[Progress] = ...,
    **options: Any,
) -> dict: ...
def simplify_file(input: PathLike, output: PathLike, *, target_faces: int, error: Optional[float] = ..., error_samples: Optional[int] = ..., no_weld: bool = ..., ascii: bool = ..., double: bool = ..., no_color: bool = ..., color_weight: Optional[float] = ..., progress: Optional[Progress] = ..., **options: Any) -> dict: ...
def boolean_file(a: PathLike, b: PathLike, op: Op, output: PathLike, *, cells: Optional[float] = ..., cell_size: Optional[float] = ..., mem: Optional[Union[str, int]] = ..., work: Optional[PathLike] = ..., progress: Optional[Progress] = ..., **options: Any) -> dict: ...
def csg_file(scene: PathLike, output: PathLike, *, cells: Optional[float] = ..., cell_size: Optional[float] = ..., mem: Optional[Union[str, int]] = ..., work: Optional[PathLike] = ..., progress: Optional[Progress] = ..., **options: Any) -> dict: ...
def check_file(inputs: Paths, *, strict: bool = ..., self_intersections: bool = ..., no_weld: bool = ..., mem: Optional[Union[str, int]] = ..., tmp: Optional[PathLike] = ..., threads: Optional[int] = ..., progress: Optional[Progress] = ..., **options: Any) -> dict: ...
def distance_file(a: PathLike, b: PathLike, *, samples: Optional[int] = ..., seed: Optional[int] = ..., progress: Optional[Progress] = ..., **options: Any) -> dict: ...
def render_file(inputs: Paths, output: PathLike, *, size: Optional[Size] = ..., view: Optional[View] = ..., up: Optional[Literal["x", "y", "z"]] = ..., color: Optional[Literal["vertex", "shading", "distance"]] = ..., wireframe: bool = ..., show_boundary: bool = ..., mem: Optional[Union[str, int]] = ..., threads: Optional[int] = ..., progress: Optional[Progress] = ..., **options: Any) -> dict: ...
def convert(inputs: Paths, output: PathLike, *, ascii: bool = ..., double: bool = ..., no_color: bool = ..., tmp: Optional[PathLike] = ..., progress: Optional[Progress] = ..., **options: Any) -> None: ...
def gen(shape: Literal["sphere", "torus", "genus", "components", "scan", "volume", "labels"], output: PathLike, *, faces: Optional[int] = ..., seed: Optional[int] = ..., genus: Optional[int] = ..., dims: Optional[str] = ..., spacing: Optional[str] = ..., ascii: bool = ..., color: bool = ..., progress: Optional[Progress] = ..., **options: Any) -> dict: ...
# A 3-D array indexed [k, j, i] (slices first, x fastest), integer or float.
Samples = npt.ArrayLike
Triple = Union[float, Sequence[float]]
def volume(
    samples: Samples,
    *,
    iso: float,
    spacing: Triple = ...,
    origin: Triple = ...,
    cells: Optional[float] = ...,
    cell_size: Optional[float] = ...,
    open_border: bool = ...,
    mem: Optional[Union[str, int]] = ...,
    threads: Optional[int] = ...,
    tmp: Optional[PathLike] = ...,
    progress: Optional[Progress] = ...,
    **options: Any,
) -> MeshResult: ...
def volume_file(
    input: PathLike,
    output: PathLike,
    *,
    iso: Optional[float] = ...,
    labels: Union[None, bool, Literal["all"], float, Sequence[float]] = ...,
    one_file: bool = ...,
    cells: Optional[float] = ...,
    cell_size: Optional[float] = ...,
    open_border: bool = ...,
    dicom_series: Optional[Union[str, int]] = ...,
    raw_dims: Optional[str] = ...,
    raw_type: Optional[Literal["u8", "i8", "u16", "i16", "u32", "i32", "u64", "i64", "f32", "f64"]] = ...,
    raw_spacing: Optional[str] = ...,
    raw_big_endian: bool = ...,
    raw_header: Optional[int] = ...,
    ascii: bool = ...,
    double: bool = ...,
    mem: Optional[Union[str, int]] = ...,
    work: Optional[PathLike] = ...,
    parts: Optional[int] = ...,
    slabs: Optional[int] = ...,
    threads: Optional[int] = ...,
    tmp: Optional[PathLike] = ...,
    progress: Optional[Progress] = ...,
    **options: Any,
) -> dict: ...
