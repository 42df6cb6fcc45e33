"""mint from Python: turn huge 3D scans into clean meshes.

Two kinds of calls, both running mint's own engine in this process (the
same code, options and output bytes as the ``mint`` command line):

* **array calls** for meshes in memory: :func:`resample`, :func:`decimate`,
  :func:`simplify`, :func:`boolean`, :func:`csg`, :func:`check`,
  :func:`distance`, :func:`render`, :func:`generate`, and :func:`volume`
  (a numpy voxel array to its iso-surface). A mesh is
  ``(vertices, faces)`` (float32/float64 ``(N, 3)`` and int32/int64/uint32
  ``(M, 3)``) or any object with ``.vertices`` and ``.faces`` (a
  ``trimesh.Trimesh``). Results are float64 vertices and int64 faces.
* **file calls** for meshes that do not fit in memory, out of core within
  ``mem``: :func:`resample_file`, :func:`decimate_file`,
  :func:`simplify_file`, :func:`boolean_file`, :func:`csg_file`,
  :func:`check_file`, :func:`distance_file`, :func:`render_file`,
  :func:`convert`, :func:`gen`, and :func:`volume_file` (CT, MRI and
  micro-CT files: NRRD, MetaImage, NIfTI, DICOM series, TIFF stacks, raw).
  They return the command's ``--json`` summary as a dict.

Options are the command line's long options with ``_`` for ``-``
(``cell_size=0.5``, ``no_color=True``, ``mem="2G"``); ``mint <command>
--help`` explains each. Long calls release the GIL, report to
``progress(phase, done, total)`` when given (return ``False`` to stop),
and stop on Ctrl-C with ``KeyboardInterrupt``, leaving no temporary file
and no partial output. Failures raise :class:`MintError` subclasses with
the command line's one-line message; bad arrays raise ``ValueError``
naming the argument.

>>> import mint_mesh
>>> v, f = mint_mesh.generate("torus", faces=20000)
>>> v2, f2 = mint_mesh.resample(v, f, cells=100000)
>>> mint_mesh.check(v2, f2)["watertight"]
True
"""

from __future__ import annotations

import json
import os
import tempfile
import warnings
from pathlib import Path
from typing import Any, Callable, Iterable, Optional, Sequence, Union

import numpy as np

from . import _mint
from ._errors import (
    BudgetError,
    CancelledError,
    InputError,
    MintError,
    MintIOError,
    MintWarning,
    UsageError,
    error_of,
)

__version__ = _mint.__version__

__all__ = [
    "resample", "decimate", "simplify", "boolean", "csg", "check", "distance", "render", "generate",
    "resample_file", "decimate_file", "simplify_file", "boolean_file", "csg_file", "check_file",
    "distance_file", "render_file", "convert", "gen", "read", "write", "run", "volume", "volume_file",
    "MeshResult", "MintError", "UsageError", "InputError", "MintIOError", "BudgetError",
    "CancelledError", "MintWarning",
]

PathLike = Union[str, "os.PathLike[str]"]
Progress = Callable[[str, int, int], Optional[bool]]

# Commands that take --tmp (where their spill files go).
_TMP = {"resample", "decimate", "bool", "csg", "check", "convert", "volume"}
# Commands whose summary comes as --json; the others run with --quiet.
_JSON = {"resample", "decimate", "simplify", "bool", "csg", "check", "distance", "render", "gen", "info", "validate", "volume"}


class MeshResult(tuple):
    """``(vertices, faces)``, or ``(vertices, faces, colors)`` when colours
    were given, with the run's summary (the command's ``--json`` fields) as
    ``.summary``. Unpacks like a tuple: ``v, f = mint_mesh.resample(...)``."""

    summary: dict

    def __new__(cls, items: Sequence[Any], summary: Optional[dict]) -> "MeshResult":
        t = super().__new__(cls, items)
        t.summary = summary or {}
        return t

    @property
    def vertices(self) -> np.ndarray:
        """float64 (N, 3) vertex positions."""
        return self[0]

    @property
    def faces(self) -> np.ndarray:
        """int64 (M, 3) vertex indices of each triangle."""
        return self[1]

    @property
    def colors(self) -> Optional[np.ndarray]:
        """uint8 (N, 3) or (N, 4) vertex colours, or None."""
        return self[2] if len(self) > 2 else None


# ---------------------------------------------------------------------------
# Running a command


def _option_args(options: dict) -> list:
    """Keyword options as command-line arguments: ``cell_size=0.5`` is
    ``--cell-size 0.5``, ``True`` a bare flag, ``False``/``None`` nothing,
    a list or tuple the option repeated (``size=(800, 600)`` is ``800x600``)."""
    argv = []
    for key, value in options.items():
        if value is None or value is False:
            continue
        name = "--" + key.replace("_", "-")
        if value is True:
            argv.append(name)
        elif key == "size" and isinstance(value, (tuple, list)):
            argv += [name, "x".join(str(int(x)) for x in value)]
        elif isinstance(value, (list, tuple)):
            for item in value:
                argv += [name, _text(item)]
        else:
            argv += [name, _text(value)]
    return argv


def _text(value: Any) -> str:
    if isinstance(value, float) and value.is_integer() and abs(value) < 2**53:
        return str(int(value))
    return os.fspath(value) if isinstance(value, os.PathLike) else str(value)


def run(argv: Sequence[str], progress: Optional[Progress] = None) -> Optional[dict]:
    """Runs one mint command line in this process (without the program
    name) and returns its ``--json`` summary (or None). Warnings become
    :class:`MintWarning`; failures raise :class:`MintError` subclasses.

    >>> import mint_mesh, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> mint_mesh.run(["gen", "sphere", os.path.join(d, "s.ply"), "--faces", "2000", "--json"])["faces"]
    2000
    """
    if progress is not None and not callable(progress):
        raise ValueError("progress: must be callable as progress(phase, done, total)")
    ok, kind, message, docs, warns = _mint.run([_text(a) for a in argv], progress)
    for w in warns:
        warnings.warn(w, MintWarning, stacklevel=3)
    if not ok:
        raise error_of(kind, message)
    return json.loads(docs[-1]) if docs else None


def _command(command: str, positional: Sequence[Any], options: dict, progress: Optional[Progress]) -> Optional[dict]:
    argv = [command] + [_text(p) for p in positional] + _option_args(options)
    argv.append("--json" if command in _JSON else "--quiet")
    return run(argv, progress)


def _paths(inputs: Union[PathLike, Iterable[PathLike]], name: str) -> list:
    if isinstance(inputs, (str, os.PathLike)):
        return [os.fspath(inputs)]
    out = [os.fspath(p) for p in inputs]
    if not out:
        raise ValueError(f"{name}: no input file")
    return out


# ---------------------------------------------------------------------------
# Arrays


def _as_mesh(vertices: Any, faces: Any, name: str, colors: Any = None):
    """Checked, contiguous arrays of a mesh given as arrays, a (v, f) pair
    or an object with .vertices and .faces."""
    if faces is None:
        m = vertices
        if hasattr(m, "vertices") and hasattr(m, "faces"):
            vertices, faces = m.vertices, m.faces
        elif isinstance(m, (tuple, list)) and len(m) in (2, 3):
            if len(m) == 3 and colors is None:
                colors = m[2]
            vertices, faces = m[0], m[1]
        else:
            raise ValueError(f"{name}: expected a mesh: (vertices, faces), or an object with .vertices and .faces")
    vname, fname = (f"{name}.vertices", f"{name}.faces") if name != "mesh" else ("vertices", "faces")
    v = np.asarray(vertices)
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"{vname}: expected shape (N, 3), got {v.shape}")
    if v.shape[0] == 0:
        raise ValueError(f"{vname}: empty")
    if v.dtype not in (np.float32, np.float64):
        if v.dtype.kind not in "iuf":
            raise ValueError(f"{vname}: expected float32 or float64, got {v.dtype}")
        v = v.astype(np.float64)
    v = np.ascontiguousarray(v)
    finite = np.isfinite(v).all(axis=1)
    if not finite.all():
        i = int(np.flatnonzero(~finite)[0])
        raise ValueError(f"{vname}: row {i} is not finite ({v[i, 0]}, {v[i, 1]}, {v[i, 2]})")
    f = np.asarray(faces)
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"{fname}: expected shape (M, 3) triangles, got {f.shape}")
    if f.shape[0] == 0:
        raise ValueError(f"{fname}: empty")
    if f.dtype not in (np.int32, np.int64, np.uint32):
        if f.dtype.kind not in "iu":
            raise ValueError(f"{fname}: expected int32, int64 or uint32 indices, got {f.dtype}")
        f = f.astype(np.int64)
    f = np.ascontiguousarray(f)
    lo, hi = int(f.min()), int(f.max())
    if lo < 0 or hi >= v.shape[0]:
        bad = lo if lo < 0 else hi
        row = int(np.argwhere(f == bad)[0, 0])
        raise ValueError(f"{fname}: row {row} refers to vertex {bad}, outside 0..{v.shape[0] - 1}")
    c = None
    if colors is not None:
        cname = "colors" if name == "mesh" else f"{name}.colors"
        c = np.asarray(colors)
        if c.ndim != 2 or c.shape[1] not in (3, 4) or c.shape[0] != v.shape[0]:
            raise ValueError(f"{cname}: expected shape ({v.shape[0]}, 3) or ({v.shape[0]}, 4), got {c.shape}")
        if c.dtype != np.uint8:
            if c.dtype.kind == "f" and np.isfinite(c).all() and c.min() >= 0 and c.max() <= 1:
                c = np.rint(c * 255)
            elif c.dtype.kind not in "iuf" or c.min() < 0 or c.max() > 255:
                raise ValueError(f"{cname}: expected uint8 values (0-255), got {c.dtype}")
            c = c.astype(np.uint8)
        c = np.ascontiguousarray(c)
    return v, f, c


def write(path: PathLike, vertices: Any, faces: Any = None, colors: Any = None) -> None:
    """Writes a mesh to a file in the format its extension names (binary
    PLY directly; other formats through :func:`convert`). float64 vertices
    are written as doubles, float32 as floats; colours as RGBA bytes.

    >>> import mint_mesh, tempfile, os
    >>> v, f = mint_mesh.generate("sphere", faces=2000)
    >>> mint_mesh.write(os.path.join(tempfile.mkdtemp(), "s.obj"), v, f)
    """
    v, f, c = _as_mesh(vertices, faces, "mesh", colors)
    path = os.fspath(path)
    if path.lower().endswith(".ply"):
        _mint.write_ply(path, v, f, c)
        return
    with tempfile.TemporaryDirectory(prefix="mint-") as d:
        tmp = os.path.join(d, "mesh.ply")
        _mint.write_ply(tmp, v, f, c)
        convert(tmp, path, double=v.dtype == np.float64 or None)


def read(path: PathLike) -> MeshResult:
    """Reads a mesh file of any format mint reads: ``(vertices, faces)``,
    or ``(vertices, faces, colors)`` when it has per-vertex colour (uint8
    RGBA). Polygons are fanned into triangles.

    >>> import mint_mesh, tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "t.ply")
    >>> _ = mint_mesh.gen("torus", p, faces=2000)
    >>> v, f = mint_mesh.read(p)
    >>> f.shape
    (2000, 3)
    """
    v, f, c = _mint.read_mesh(os.fspath(path))
    return MeshResult((v, f) if c is None else (v, f, c), None)


# Array calls keep their scratch files in memory (tmpfs) when it has room
# for this many times the arrays' bytes: the input, the output and the
# engine's shards never touch a disk, as the arrays themselves do not.
_SHM = "/dev/shm"
_SHM_ROOM = 8


def _scratch_root(need: int) -> Optional[str]:
    try:
        st = os.statvfs(_SHM)
    except OSError:
        return None
    if os.access(_SHM, os.W_OK) and st.f_bavail * st.f_frsize >= _SHM_ROOM * need:
        return _SHM
    return None


class _Scratch:
    """A temporary directory for one array call: removed on return, error
    and Ctrl-C. ``tmp`` (the option) chooses where it lives; by default
    /dev/shm when it has room for the meshes (``meshes``), else the
    system's temporary directory."""

    def __init__(self, options: dict, meshes: Sequence[tuple] = ()):
        where = options.pop("tmp", None)
        if where is None:
            where = _scratch_root(sum(m[0].nbytes + m[1].nbytes for m in meshes))
        self._dir = tempfile.TemporaryDirectory(prefix="mint-", dir=os.fspath(where) if where else None)
        self.path = self._dir.name

    def opts(self, command: str, options: dict) -> dict:
        """``options`` with the command's own spill files in here too."""
        return dict(options, tmp=self.path) if command in _TMP else options

    def __enter__(self) -> "_Scratch":
        return self

    def __exit__(self, *exc) -> None:
        self._dir.cleanup()

    def file(self, name: str) -> str:
        return os.path.join(self.path, name)

    def mesh(self, mesh: tuple, name: str) -> str:
        p = self.file(name + ".ply")
        _mint.write_ply(p, *mesh)
        return p


def _result(path: str, colors_in: Optional[np.ndarray], summary: Optional[dict], keep_colors: bool) -> MeshResult:
    v, f, c = _mint.read_mesh(path)
    if colors_in is None or not keep_colors:
        return MeshResult((v, f), summary)
    if c is None:
        c = np.full((v.shape[0], 4), 255, np.uint8)
    return MeshResult((v, f, c[:, : colors_in.shape[1]].copy()), summary)


def _array_job(command: str, mesh: tuple, extra: Sequence[Any], options: dict, progress: Optional[Progress]) -> MeshResult:
    with _Scratch(options, [mesh]) as s:
        inp = s.mesh(mesh, "in")
        out = s.file("out.ply")
        summary = _command(command, [inp, *extra, out], s.opts(command, options), progress)
        return _result(out, mesh[2], summary, not options.get("no_color"))


def resample(vertices: Any, faces: Any = None, *, colors: Any = None, cells: Optional[float] = None,
             progress: Optional[Progress] = None, **options: Any) -> MeshResult:
    """Marching Intersections resampling: a watertight, 2-manifold,
    outward-oriented mesh of the input on a regular grid of about ``cells``
    cubic cells (or ``cell_size``). Detail smaller than a cell goes, holes
    close; open sheets stay open (``signs="auto"``). Options as ``mint
    resample`` (``cell_size``, ``signs``, ``max_hole``, ``close_all``,
    ``double``, ``mem``, ``threads``, ``tmp``...). Returns ``(vertices,
    faces)`` (with ``colors`` when given) and ``.summary``.

    >>> import mint_mesh
    >>> v, f = mint_mesh.generate("sphere", faces=20000)
    >>> r = mint_mesh.resample(v, f, cells=50000)
    >>> r.summary["output_faces"] == len(r.faces)
    True
    """
    mesh = _as_mesh(vertices, faces, "mesh", colors)
    return _array_job("resample", mesh, [], dict(options, cells=cells), progress)


def decimate(vertices: Any, faces: Any = None, *, target_faces: int, colors: Any = None,
             progress: Optional[Progress] = None, **options: Any) -> MeshResult:
    """Decimates to about ``target_faces`` faces as ``mint decimate``: a
    clean solid (closed, 2-manifold, oriented) that fits is simplified
    itself; anything else is resampled to an intermediate mesh first
    (closes holes, drops detail below the target's scale), then quadric
    edge collapse. ``.summary["route"]`` says which ran and why, and
    ``.summary["error"]`` what it cost (sampled distance to the input;
    ``error_samples=0`` leaves it out, and it is then None).
    Options: ``route`` ("auto", "direct", "resample"), ``intermediate``,
    ``error``, ``error_samples``, ``color_weight``, ``no_color``, ``mem``,
    ``threads``...

    >>> import mint_mesh
    >>> v, f = mint_mesh.generate("torus", faces=100000)
    >>> v2, f2 = mint_mesh.decimate(v, f, target_faces=5000)
    >>> abs(len(f2) - 5000) <= 100
    True
    """
    mesh = _as_mesh(vertices, faces, "mesh", colors)
    return _array_job("decimate", mesh, [], dict(options, faces=_count(target_faces, "target_faces")), progress)


def simplify(vertices: Any, faces: Any = None, *, target_faces: int, colors: Any = None,
             progress: Optional[Progress] = None, **options: Any) -> MeshResult:
    """Quadric edge collapse (Garland-Heckbert, f64) of a mesh that fits in
    memory to about ``target_faces`` faces, as ``mint simplify``: keeps a
    closed, oriented 2-manifold so; boundaries slide along themselves.
    Options: ``error``, ``error_samples`` (samples per direction of the
    summary's sampled error; 0 leaves it out, the faster call),
    ``no_weld``, ``color_weight``, ``no_color``.

    >>> import mint_mesh
    >>> v, f = mint_mesh.generate("sphere", faces=20000)
    >>> v2, f2 = mint_mesh.simplify(v, f, target_faces=2000)
    >>> len(f2)
    2000
    """
    mesh = _as_mesh(vertices, faces, "mesh", colors)
    options = dict(options, faces=_count(target_faces, "target_faces"))
    if mesh[0].dtype == np.float64:
        options.setdefault("double", True)
    return _array_job("simplify", mesh, [], options, progress)


_OPS = ("union", "intersection", "difference")


def boolean(a: Any, b: Any, op: str, *, cells: Optional[float] = None,
            progress: Optional[Progress] = None, **options: Any) -> MeshResult:
    """Boolean of two closed meshes on one grid (``op``: "union",
    "intersection" or "difference", A minus B), computed on the grid's
    intersection lists as ``mint bool``: watertight output. ``a`` and ``b``
    are meshes ((vertices, faces) or objects with .vertices/.faces).

    >>> import mint_mesh
    >>> a = mint_mesh.generate("sphere", faces=20000)
    >>> b = mint_mesh.generate("torus", faces=20000)
    >>> v, f = mint_mesh.boolean(a, b, "union", cells=100000)
    >>> mint_mesh.check(v, f)["watertight"]
    True
    """
    if op not in _OPS:
        raise ValueError(f"op: expected one of {', '.join(_OPS)}, got {op!r}")
    ma, mb = _as_mesh(a, None, "a"), _as_mesh(b, None, "b")
    with _Scratch(options, [ma, mb]) as s:
        pa, pb = s.mesh(ma, "a"), s.mesh(mb, "b")
        out = s.file("out.ply")
        summary = _command("bool", [op, pa, pb, out], s.opts("bool", dict(options, cells=cells)), progress)
        return _result(out, None, summary, False)


def csg(scene: Union[dict, str], *, cells: Optional[float] = None, progress: Optional[Progress] = None,
        **options: Any) -> MeshResult:
    """Meshes a CSG scene as ``mint csg``: a tree (dict, or JSON text) of
    primitives (sphere, box, cylinder, cone, torus, halfspace) and meshes
    under union, intersection and difference, with transforms. A ``"mesh"``
    node may hold a mesh ((vertices, faces) or a trimesh) instead of a path.

    >>> import mint_mesh
    >>> v, f = mint_mesh.csg({"difference": [{"box": {"size": [2, 2, 2]}}, {"sphere": {"radius": 1.2}}]}, cells=50000)
    >>> mint_mesh.check(v, f)["watertight"]
    True
    """
    if isinstance(scene, str):
        try:
            scene = json.loads(scene)
        except json.JSONDecodeError as e:
            raise ValueError(f"scene: not JSON: {e}") from None
    if not isinstance(scene, dict):
        raise ValueError("scene: expected a dict (or its JSON text)")
    with _Scratch(options) as s:
        count = [0]

        def place(node: Any) -> Any:
            if isinstance(node, dict):
                out = {}
                for k, val in node.items():
                    if k == "mesh" and not isinstance(val, (str, os.PathLike)):
                        count[0] += 1
                        out[k] = s.mesh(_as_mesh(val, None, f"mesh {count[0]}"), f"m{count[0]}")
                    elif k == "mesh":
                        out[k] = os.path.abspath(os.fspath(val))
                    else:
                        out[k] = place(val)
                return out
            if isinstance(node, list):
                return [place(x) for x in node]
            return node

        p = s.file("scene.json")
        with open(p, "w") as fh:
            json.dump(place(scene), fh)
        out = s.file("out.ply")
        summary = _command("csg", [p, out], s.opts("csg", dict(options, cells=cells)), progress)
        return _result(out, None, summary, False)


def check(vertices: Any, faces: Any = None, *, progress: Optional[Progress] = None, **options: Any) -> dict:
    """Judges a mesh as ``mint check --json``: counts, components,
    boundary and non-manifold edges, orientation, degenerate and duplicate
    faces, genus, volume, and ``watertight``. Options: ``no_weld``,
    ``self_intersections``, ``mem``.

    >>> import mint_mesh
    >>> r = mint_mesh.check(*mint_mesh.generate("torus", faces=2000))
    >>> r["watertight"], r["genus_total"]
    (True, 1)
    """
    mesh = _as_mesh(vertices, faces, "mesh")
    with _Scratch(options, [mesh]) as s:
        return _command("check", [s.mesh(mesh, "mesh")], s.opts("check", options), progress)


def distance(a: Any, b: Any, *, progress: Optional[Progress] = None, **options: Any) -> dict:
    """Metro-style surface distance between two meshes, both directions, as
    ``mint distance --json`` (``samples``, ``seed``).

    >>> import mint_mesh
    >>> a = mint_mesh.generate("sphere", faces=20000)
    >>> d = mint_mesh.distance(a, mint_mesh.simplify(*a, target_faces=2000))
    >>> d["a_to_b"]["max"] < 0.05
    True
    """
    ma, mb = _as_mesh(a, None, "a"), _as_mesh(b, None, "b")
    with _Scratch(options, [ma, mb]) as s:
        return _command("distance", [s.mesh(ma, "a"), s.mesh(mb, "b")], options, progress)


def render(meshes: Any, *, size: Any = None, view: Optional[str] = None, path: Optional[PathLike] = None,
           progress: Optional[Progress] = None, **options: Any) -> np.ndarray:
    """A picture of one mesh or of several side by side (a list), as ``mint
    render``: a (H, W, 3) uint8 array. With ``path``, the PNG is also
    written there (the same bytes as the command line). Options: ``size``
    ("800x600" or (800, 600)), ``view`` (iso, front, ..., all), ``up``,
    ``color``, ``wireframe``, ``show_boundary``.

    >>> import mint_mesh
    >>> img = mint_mesh.render(mint_mesh.generate("torus", faces=2000), size=(320, 240))
    >>> img.shape, img.dtype
    ((240, 320, 3), dtype('uint8'))
    """
    if hasattr(meshes, "vertices") or (isinstance(meshes, tuple) and len(meshes) in (2, 3) and isinstance(meshes[0], np.ndarray)):
        meshes = [meshes]
    meshes = list(meshes)
    if not meshes:
        raise ValueError("meshes: no mesh to draw")
    checked = [_as_mesh(m, None, f"meshes[{i}]") for i, m in enumerate(meshes)]
    with _Scratch(options, checked) as s:
        files = [s.mesh(m, f"m{i}") for i, m in enumerate(checked)]
        out = os.fspath(path) if path is not None else s.file("picture.png")
        _command("render", [*files, out], dict(options, size=size, view=view), progress)
        img = _mint.read_png(out)
    return np.ascontiguousarray(img[:, :, :3])


def generate(shape: str, *, faces: Optional[int] = None, **options: Any) -> MeshResult:
    """A synthetic mesh as arrays (``mint gen``): "sphere", "torus",
    "genus" (``genus=``), "components", "scan" (holes, flips, slivers).

    >>> import mint_mesh
    >>> v, f = mint_mesh.generate("sphere", faces=2000)
    >>> v.dtype, f.dtype, f.shape
    (dtype('float64'), dtype('int64'), (2000, 3))
    """
    with _Scratch(options) as s:
        out = s.file("gen.ply")
        summary = gen(shape, out, faces=faces, **options)
        return _result(out, None, summary, False)


def _count(n: Any, name: str) -> int:
    try:
        k = int(n)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a face count, got {n!r}") from None
    if k != n or k < 1:
        raise ValueError(f"{name}: expected a positive whole number, got {n!r}")
    return k


# ---------------------------------------------------------------------------
# Files


def resample_file(inputs: Union[PathLike, Iterable[PathLike]], output: PathLike, *, cells: Optional[float] = None,
                  mem: Optional[str] = None, work: Optional[PathLike] = None, parts: Optional[int] = None,
                  slabs: Optional[int] = None, progress: Optional[Progress] = None, **options: Any) -> dict:
    """``mint resample``, out of core within ``mem`` ("4G"): one file,
    several (tiles of one surface), a directory or "@list". ``work`` keeps
    the run's stages there (resumable). Returns the ``--json`` summary.

    >>> import mint_mesh, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> _ = mint_mesh.gen("scan", os.path.join(d, "scan.ply"), faces=20000)
    >>> s = mint_mesh.resample_file(os.path.join(d, "scan.ply"), os.path.join(d, "out.ply"), cells=50000, mem="256M")
    >>> s["output_faces"] > 0
    True
    """
    opts = dict(options, cells=cells, mem=mem, work=work, parts=parts, slabs=slabs)
    return _command("resample", [*_paths(inputs, "inputs"), output], opts, progress)


def decimate_file(inputs: Union[PathLike, Iterable[PathLike]], output: PathLike, *, target_faces: int,
                  mem: Optional[str] = None, progress: Optional[Progress] = None, **options: Any) -> dict:
    """``mint decimate``: a mesh of any size to about ``target_faces``
    faces within ``mem``. Returns the ``--json`` summary.

    >>> import mint_mesh, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> _ = mint_mesh.gen("torus", os.path.join(d, "t.ply"), faces=100000)
    >>> mint_mesh.decimate_file(os.path.join(d, "t.ply"), os.path.join(d, "small.ply"), target_faces=5000)["output_faces"] <= 5100
    True
    """
    opts = dict(options, faces=_count(target_faces, "target_faces"), mem=mem)
    return _command("decimate", [*_paths(inputs, "inputs"), output], opts, progress)


def simplify_file(input: PathLike, output: PathLike, *, target_faces: int, progress: Optional[Progress] = None,
                  **options: Any) -> dict:
    """``mint simplify``: quadric edge collapse of a mesh file that fits in
    memory. Returns the ``--json`` summary.

    >>> import mint_mesh, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> _ = mint_mesh.gen("sphere", os.path.join(d, "s.ply"), faces=20000)
    >>> mint_mesh.simplify_file(os.path.join(d, "s.ply"), os.path.join(d, "small.ply"), target_faces=2000)["output_faces"]
    2000
    """
    return _command("simplify", [input, output], dict(options, faces=_count(target_faces, "target_faces")), progress)


def boolean_file(a: PathLike, b: PathLike, op: str, output: PathLike, *, cells: Optional[float] = None,
                 progress: Optional[Progress] = None, **options: Any) -> dict:
    """``mint bool OP A B OUT``, out of core. Returns the ``--json`` summary.

    >>> import mint_mesh, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> a, b = os.path.join(d, "a.ply"), os.path.join(d, "b.ply")
    >>> _ = mint_mesh.gen("sphere", a, faces=20000); _ = mint_mesh.gen("torus", b, faces=20000)
    >>> mint_mesh.boolean_file(a, b, "difference", os.path.join(d, "out.ply"), cells=100000)["output_faces"] > 0
    True
    """
    if op not in _OPS:
        raise ValueError(f"op: expected one of {', '.join(_OPS)}, got {op!r}")
    return _command("bool", [op, a, b, output], dict(options, cells=cells), progress)


def csg_file(scene: PathLike, output: PathLike, *, cells: Optional[float] = None, progress: Optional[Progress] = None,
             **options: Any) -> dict:
    """``mint csg SCENE.json OUT``. Returns the ``--json`` summary.

    >>> import mint_mesh, tempfile, os, json
    >>> d = tempfile.mkdtemp()
    >>> with open(os.path.join(d, "scene.json"), "w") as f:
    ...     json.dump({"union": [{"sphere": {"radius": 1}}, {"box": {"size": [1, 1, 3]}}]}, f)
    >>> mint_mesh.csg_file(os.path.join(d, "scene.json"), os.path.join(d, "out.ply"), cells=50000)["output_faces"] > 0
    True
    """
    return _command("csg", [scene, output], dict(options, cells=cells), progress)


def check_file(inputs: Union[PathLike, Iterable[PathLike]], *, progress: Optional[Progress] = None,
               **options: Any) -> dict:
    """``mint check --json`` of a file (or tiles of one surface), within
    ``mem``: the verdict ``watertight`` and what spoils it.

    >>> import mint_mesh, tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "scan.ply")
    >>> _ = mint_mesh.gen("scan", p, faces=20000)
    >>> r = mint_mesh.check_file(p, mem="64M")
    >>> r["watertight"], r["boundary_edges"] > 0
    (False, True)
    """
    return _command("check", _paths(inputs, "inputs"), options, progress)


def distance_file(a: PathLike, b: PathLike, *, progress: Optional[Progress] = None, **options: Any) -> dict:
    """``mint distance --json`` between two mesh files.

    >>> import mint_mesh, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> _ = mint_mesh.gen("sphere", os.path.join(d, "s.ply"), faces=20000)
    >>> _ = mint_mesh.simplify_file(os.path.join(d, "s.ply"), os.path.join(d, "t.ply"), target_faces=2000)
    >>> mint_mesh.distance_file(os.path.join(d, "s.ply"), os.path.join(d, "t.ply"), samples=10000)["a_to_b"]["max"] < 0.05
    True
    """
    return _command("distance", [a, b], options, progress)


def render_file(inputs: Union[PathLike, Iterable[PathLike]], output: PathLike, *, progress: Optional[Progress] = None,
                **options: Any) -> dict:
    """``mint render``: a PNG of meshes of any size (streamed). Returns the
    ``--json`` summary.

    >>> import mint_mesh, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> _ = mint_mesh.gen("torus", os.path.join(d, "t.ply"), faces=20000)
    >>> _ = mint_mesh.render_file(os.path.join(d, "t.ply"), os.path.join(d, "t.png"), size="400x300", view="all")
    >>> os.path.getsize(os.path.join(d, "t.png")) > 0
    True
    """
    return _command("render", [*_paths(inputs, "inputs"), output], options, progress)


def convert(inputs: Union[PathLike, Iterable[PathLike]], output: PathLike, *, progress: Optional[Progress] = None,
            **options: Any) -> None:
    """``mint convert``: between PLY, OBJ, STL, OFF, glTF..., streaming
    (``ascii``, ``double``, ``no_color``).

    >>> import mint_mesh, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> _ = mint_mesh.gen("torus", os.path.join(d, "t.ply"), faces=2000)
    >>> mint_mesh.convert(os.path.join(d, "t.ply"), os.path.join(d, "t.glb"))
    >>> len(mint_mesh.read(os.path.join(d, "t.glb")).faces)
    2000
    """
    _command("convert", [*_paths(inputs, "inputs"), output], options, progress)


def gen(shape: str, output: PathLike, *, progress: Optional[Progress] = None, **options: Any) -> dict:
    """``mint gen``: a synthetic mesh file of any size ("sphere", "torus",
    "genus", "components", "scan"; ``faces``, ``seed``, ``genus``,
    ``color``). Returns the ``--json`` summary.

    >>> import mint_mesh, tempfile, os
    >>> mint_mesh.gen("torus", os.path.join(tempfile.mkdtemp(), "t.ply"), faces=2000)["genus"]
    1
    """
    return _command("gen", [shape, output], options, progress)


# ---------------------------------------------------------------------------
# Volumes

# numpy dtypes `mint volume --raw-type` reads.
_RAW_TYPES = {"u1": "u8", "i1": "i8", "u2": "u16", "i2": "i16", "u4": "u32", "i4": "i32",
              "u8": "u64", "i8": "i64", "f4": "f32", "f8": "f64"}


def _triple(value: Any, name: str, positive: bool) -> tuple:
    try:
        t = tuple(float(x) for x in (value if isinstance(value, (list, tuple, np.ndarray)) else [value] * 3))
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected three numbers, got {value!r}") from None
    if len(t) != 3 or not all(np.isfinite(t)) or (positive and not all(x > 0 for x in t)):
        raise ValueError(f"{name}: expected three finite{' positive' if positive else ''} numbers, got {value!r}")
    return t


def volume(samples: Any, *, iso: float, spacing: Any = (1.0, 1.0, 1.0), origin: Any = (0.0, 0.0, 0.0),
           progress: Optional[Progress] = None, **options: Any) -> MeshResult:
    """The iso-surface of a voxel array, as ``mint volume``: a closed,
    oriented 2-manifold (the array's border counts as outside; pass
    ``open_border=True`` to leave it open there). ``samples`` is a 3-D
    array indexed ``[k, j, i]`` (slices first, x fastest: the order of
    ``pydicom``/``SimpleITK``'s arrays and of raw files) of any integer or
    float type; samples ``>= iso`` are inside, NaN is outside. Vertex ``(i,
    j, k)`` lands at ``origin + (i, j, k) * spacing`` (x, y, z). Options as
    ``mint volume`` (``cells`` or ``cell_size`` for a coarser or finer grid
    sampled trilinearly, ``open_border``, ``mem``, ``threads``...).

    >>> import mint_mesh, numpy as np
    >>> z, y, x = np.mgrid[:32, :32, :32]
    >>> field = 10 - np.sqrt((x - 15.5) ** 2 + (y - 15.5) ** 2 + (z - 15.5) ** 2)
    >>> v, f = mint_mesh.volume(field, iso=0, spacing=(0.5, 0.5, 0.5))
    >>> mint_mesh.check(v, f)["watertight"]
    True
    """
    a = np.asarray(samples)
    if a.ndim != 3 or 0 in a.shape:
        raise ValueError(f"samples: expected a non-empty 3-D array indexed [k, j, i], got shape {a.shape}")
    if a.dtype == np.bool_:
        a = a.astype(np.uint8)
    kind = _RAW_TYPES.get(a.dtype.str[1:])
    if kind is None:
        raise ValueError(f"samples: dtype {a.dtype} is not an integer or float type mint reads")
    try:
        iso = float(iso)
    except (TypeError, ValueError):
        raise ValueError(f"iso: expected a number, got {iso!r}") from None
    if not np.isfinite(iso):
        raise ValueError(f"iso: expected a finite number, got {iso!r}")
    sp = _triple(spacing, "spacing", True)
    org = _triple(origin, "origin", False)
    nz, ny, nx = a.shape
    with _Scratch(options) as s:
        raw = s.file("in.raw")
        np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<")).tofile(raw)
        out = s.file("out.ply")
        opts = dict(options, iso=iso, raw_dims=f"{nx},{ny},{nz}", raw_type=kind,
                    raw_spacing=",".join(repr(x) for x in sp))
        summary = _command("volume", [raw, out], s.opts("volume", opts), progress)
        r = _result(out, None, summary, False)
    v = r.vertices
    if any(org):
        v += np.asarray(org)
    return r


def volume_file(input: PathLike, output: PathLike, *, iso: Optional[float] = None, labels: Any = None,
                progress: Optional[Progress] = None, **options: Any) -> dict:
    """``mint volume``, out of core within ``mem``: a NRRD, MetaImage,
    NIfTI-1, DICOM series (a folder of single-frame files or an enhanced
    multi-frame file; uncompressed, RLE or JPEG Baseline/Lossless), TIFF
    stack or raw file (``raw_dims``, ``raw_type``, ``raw_spacing``) to its
    surface at ``iso``, in the frame
    the file declares (the summary's ``volume.frame``), or with ``labels``
    (``True`` or "all" for every label but 0, or a list such as ``[1, 2]``)
    one surface per label, one file each unless ``one_file=True``. Of a
    DICOM folder that holds several series, ``dicom_series`` picks one (its
    SeriesInstanceUID, or its number from 1 in the list the error gives
    without it); a ``.dcm`` file as ``input`` picks its own series. Options
    as ``mint volume`` (``cells``, ``cell_size``, ``open_border``,
    ``mem``, ``threads``, ``work``...). Returns the ``--json`` summary (for
    labels: ``{"labels": [...]}``).

    >>> import mint_mesh, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> _ = mint_mesh.gen("volume", os.path.join(d, "v.nhdr"), dims="48,48,48")
    >>> s = mint_mesh.volume_file(os.path.join(d, "v.nhdr"), os.path.join(d, "v.ply"), iso=1000)
    >>> s["output_faces"] > 0
    True
    """
    if (iso is None) == (labels is None or labels is False):
        raise ValueError("give one of iso= (an iso-surface) and labels= (a label map)")
    opts = dict(options, iso=iso)
    argv_labels: list = []
    if labels is True or labels == "all":
        argv_labels = ["--labels", "all"]
    elif labels is not None and labels is not False:
        values = [labels] if isinstance(labels, (int, float)) else list(labels)
        if not values:
            raise ValueError("labels: an empty list")
        argv_labels = ["--labels", ",".join(_text(x) for x in values)]
    argv = ["volume", _text(input), _text(output)] + argv_labels + _option_args(opts) + ["--json"]
    return run(argv, progress)
