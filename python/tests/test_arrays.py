"""The array calls: results, the dtype and layout matrix, colours, trimesh
objects in and out, and one ValueError per bad argument."""

import doctest

import numpy as np
import pytest

import mint_mesh


def test_resample_is_watertight_and_matches_its_summary(torus):
    r = mint_mesh.resample(*torus, cells=100000)
    v, f = r
    assert v.dtype == np.float64 and f.dtype == np.int64
    assert v.shape[1] == 3 and f.shape[1] == 3
    assert r.summary["output_faces"] == len(f) and r.summary["output_vertices"] == len(v)
    c = mint_mesh.check(v, f)
    assert c["watertight"] and c["genus_total"] == 1
    # Every output vertex lies on the torus (radii 1 and 0.35 around z).
    ring = np.hypot(np.hypot(v[:, 0], v[:, 1]) - 1.0, v[:, 2])
    assert np.abs(ring - 0.35).max() < 0.01


def test_dtype_and_layout_matrix_gives_the_same_bytes(torus):
    v, f = torus
    v = v.astype(np.float32).astype(np.float64)  # exactly representable in f32
    ref = mint_mesh.resample(v, f, cells=50000)
    variants = []
    for vd in (np.float32, np.float64):
        for fd in (np.int32, np.int64, np.uint32):
            variants.append((v.astype(vd), f.astype(fd)))
    variants.append((np.asfortranarray(v), np.asfortranarray(f)))          # not C-contiguous
    variants.append((np.hstack([v, v])[:, :3], f[:, [0, 1, 2]]))            # strided views
    variants.append((v.tolist(), f.tolist()))                                # plain lists
    for vv, ff in variants:
        r = mint_mesh.resample(vv, ff, cells=50000)
        assert np.array_equal(r.vertices, ref.vertices), (np.asarray(vv).dtype, np.asarray(ff).dtype)
        assert np.array_equal(r.faces, ref.faces)


def test_array_call_gives_the_cli_bytes(torus, tmp_path, mint_exe):
    import subprocess

    v, f = torus
    mint_mesh.write(tmp_path / "in.ply", v, f)
    subprocess.run([mint_exe, "resample", str(tmp_path / "in.ply"), str(tmp_path / "cli.ply"), "--cells", "70000", "--quiet"], check=True)
    cv, cf = mint_mesh.read(tmp_path / "cli.ply")
    r = mint_mesh.resample(v, f, cells=70000)
    assert np.array_equal(r.vertices, cv) and np.array_equal(r.faces, cf)


def test_decimate_and_simplify_hit_the_target(torus):
    v, f = mint_mesh.decimate(*torus, target_faces=3000)
    assert abs(len(f) - 3000) <= 60
    assert mint_mesh.check(v, f)["watertight"]
    v, f = mint_mesh.simplify(*torus, target_faces=3000)
    assert len(f) == 3000
    assert mint_mesh.check(v, f)["watertight"]
    d = mint_mesh.distance(torus, (v, f))
    assert d["a_to_b"]["max"] < 0.05 and d["b_to_a"]["max"] < 0.05


def test_simplify_without_the_error_measurement_gives_the_same_mesh(torus):
    measured = mint_mesh.simplify(*torus, target_faces=3000)
    unmeasured = mint_mesh.simplify(*torus, target_faces=3000, error_samples=0)
    assert measured.summary["error"]["samples"] == 50000
    assert unmeasured.summary["error"] is None
    assert np.array_equal(measured.vertices, unmeasured.vertices) and np.array_equal(measured.faces, unmeasured.faces)


def test_simplify_keeps_float64_precision():
    v, f = mint_mesh.generate("sphere", faces=5000)
    far = v + np.array([6.0e6, 4.0e6, 100.0])  # geo-referenced: f32 would round to 0.5
    s = mint_mesh.simplify(far, f, target_faces=1000)
    r = np.linalg.norm(s.vertices - np.array([6.0e6, 4.0e6, 100.0]), axis=1)
    assert np.abs(r - 1.0).max() < 0.01


def test_boolean_and_csg(sphere, torus):
    for op in ("union", "intersection", "difference"):
        v, f = mint_mesh.boolean(sphere, torus, op, cells=100000)
        assert mint_mesh.check(v, f)["watertight"], op
    scene = {"difference": [{"box": {"size": [2, 2, 2]}}, {"mesh": sphere, "scale": 1.5}]}
    v, f = mint_mesh.csg(scene, cells=50000)
    c = mint_mesh.check(v, f)
    assert c["watertight"] and c["components"] == 8  # the box's eight corners remain (edges at 1.41 < 1.5)


def test_colours_in_and_out(sphere):
    v, f = sphere
    red = np.tile(np.array([[200, 10, 10]], np.uint8), (len(v), 1))
    red[v[:, 2] > 0] = [10, 10, 200]  # blue north
    r = mint_mesh.resample(v, f, colors=red, cells=50000)
    assert r.colors is not None and r.colors.shape == (len(r.vertices), 3) and r.colors.dtype == np.uint8
    north = r.vertices[:, 2] > 0.1
    south = r.vertices[:, 2] < -0.1
    assert (r.colors[north] == [10, 10, 200]).all() and (r.colors[south] == [200, 10, 10]).all()
    d = mint_mesh.decimate(v, f, colors=red, target_faces=2000)
    assert d.colors.shape == (len(d.vertices), 3)
    assert (d.colors[d.vertices[:, 2] < -0.2] == [200, 10, 10]).all()
    rgba = np.hstack([red, np.full((len(v), 1), 255, np.uint8)])
    assert mint_mesh.resample(v, f, colors=rgba, cells=20000).colors.shape[1] == 4
    assert len(mint_mesh.resample(v, f, colors=red, cells=20000, no_color=True)) == 2


def test_trimesh_in_and_out(torus):
    import trimesh  # a test dependency (pip install "./python[test]"): missing fails, never skips
    mesh = trimesh.Trimesh(vertices=torus[0], faces=torus[1], process=False)
    v, f = mint_mesh.resample(mesh, cells=100000)
    out = trimesh.Trimesh(vertices=v, faces=f, process=False)
    assert out.is_watertight and out.is_winding_consistent and out.volume > 0
    assert mint_mesh.check(out)["watertight"]
    # trimesh keeps our arrays without a copy.
    assert np.shares_memory(out.vertices, v) or np.array_equal(out.vertices, v)
    small = mint_mesh.decimate(mesh, target_faces=2000)
    assert trimesh.Trimesh(*small, process=False).is_watertight


def test_render_array_and_file(torus, tmp_path):
    img = mint_mesh.render(torus, size=(200, 150))
    assert img.shape == (150, 200, 3) and img.dtype == np.uint8
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 10  # shaded, not blank
    img2 = mint_mesh.render([torus, torus], size=(200, 150), path=tmp_path / "p.png")
    assert img2.shape[1] >= 2 * 200 - 1 and (tmp_path / "p.png").stat().st_size > 0


def test_read_write_round_trip(tmp_path, torus):
    for name in ("m.ply", "m.obj", "m.off", "m.stl"):
        mint_mesh.write(tmp_path / name, *torus)
        v, f = mint_mesh.read(tmp_path / name)[:2]
        assert len(f) == len(torus[1]), name
        if name != "m.stl":  # STL stores f32 positions per facet
            assert np.abs(v - torus[0]).max() < 1e-6, name


BAD = [
    ("vertices", lambda v, f: (v[:, :2], f), "expected shape (N, 3)"),
    ("vertices", lambda v, f: (v[:0], f), "empty"),
    ("vertices", lambda v, f: (np.where(np.arange(len(v))[:, None] == 7, np.nan, v), f), "row 7 is not finite"),
    ("vertices", lambda v, f: (np.full(v.shape, np.inf), f), "not finite"),
    ("vertices", lambda v, f: (v.astype(str), f), "expected float32 or float64"),
    ("faces", lambda v, f: (v, f[:, :2]), "expected shape (M, 3)"),
    ("faces", lambda v, f: (v, f[:0]), "empty"),
    ("faces", lambda v, f: (v, np.where(f == 5, len(v), f)), "outside 0.."),
    ("faces", lambda v, f: (v, np.where(f == 5, -1, f)), "refers to vertex -1"),
    ("faces", lambda v, f: (v, f.astype(np.float64)), "expected int32, int64 or uint32"),
]


@pytest.mark.parametrize("arg,spoil,message", BAD, ids=[b[2] for b in BAD])
def test_bad_arrays_raise_value_error_naming_the_argument(torus, arg, spoil, message):
    v, f = spoil(*torus)
    for call in (lambda: mint_mesh.resample(v, f, cells=1000), lambda: mint_mesh.check(v, f),
                 lambda: mint_mesh.simplify(v, f, target_faces=10)):
        with pytest.raises(ValueError) as e:
            call()
        assert str(e.value).startswith(arg + ":") and message in str(e.value)


def test_other_bad_arguments(torus):
    with pytest.raises(ValueError, match="^op: expected one of"):
        mint_mesh.boolean(torus, torus, "xor")
    with pytest.raises(ValueError, match="^target_faces:"):
        mint_mesh.simplify(*torus, target_faces=0)
    with pytest.raises(ValueError, match="^target_faces:"):
        mint_mesh.decimate(*torus, target_faces="many")
    with pytest.raises(ValueError, match="^colors: expected shape"):
        mint_mesh.resample(*torus, colors=np.zeros((3, 3), np.uint8), cells=1000)
    with pytest.raises(ValueError, match="^mesh: expected a mesh"):
        mint_mesh.resample(42, cells=1000)
    with pytest.raises(ValueError, match="^b.faces:"):
        mint_mesh.boolean(torus, (torus[0], torus[1][:, :1]), "union", cells=1000)
    with pytest.raises(ValueError, match="^progress: must be callable"):
        mint_mesh.resample(*torus, cells=1000, progress=3)
    # An unknown option is the command line's usage error, a ValueError too.
    with pytest.raises(mint_mesh.UsageError, match="unexpected argument '--bogus'"):
        mint_mesh.resample(*torus, cells=1000, bogus=1)
    with pytest.raises(ValueError, match="invalid value"):
        mint_mesh.resample(*torus, cells="lots")


def test_docstring_examples_run():
    failures, tried = doctest.testmod(mint_mesh, optionflags=doctest.ELLIPSIS)
    assert tried >= 15 and failures == 0
