"""Voxel volumes from Python: `volume` on numpy arrays and `volume_file` on
the formats `mint volume` reads, with the CLI's bytes, summaries and
one-line errors."""

import json
import subprocess

import numpy as np
import pytest

import mint_mesh


def ball(n=24, r=8.0):
    z, y, x = np.mgrid[:n, :n, :n]
    c = (n - 1) / 2
    return r - np.sqrt((x - c) ** 2 + (y - c) ** 2 + (z - c) ** 2)


def test_an_array_gives_a_closed_surface_where_spacing_and_origin_put_it():
    f = ball()
    v, t = mint_mesh.volume(f, iso=0.0, spacing=(0.5, 0.25, 2.0), origin=(100.0, -20.0, 5.0))
    c = mint_mesh.check(v, t)
    assert c["watertight"] and c["genus_total"] == 0 and c["signed_volume"] > 0
    # Index (i, j, k) lands at origin + (i, j, k) * spacing: the ball's centre
    # (11.5 voxels on each axis) and radius (8 voxels) scale per axis.
    centre = np.array([100 + 11.5 * 0.5, -20 + 11.5 * 0.25, 5 + 11.5 * 2.0])
    d = (v - centre) / np.array([0.5, 0.25, 2.0])
    r = np.linalg.norm(d, axis=1)
    assert abs(r.mean() - 8.0) < 0.1 and r.max() < 8.3


def test_sample_types_give_the_same_bytes_as_each_other():
    f = (ball() > 0).astype(np.uint8) * 200
    ref = mint_mesh.volume(f, iso=100)
    for dt in (np.int16, np.uint16, np.int32, np.float32, np.float64, ">i2"):
        r = mint_mesh.volume(f.astype(dt), iso=100)
        assert np.array_equal(r.vertices, ref.vertices), dt
        assert np.array_equal(r.faces, ref.faces), dt
    # Booleans are 0/1; a non-contiguous view reads the same samples.
    b = mint_mesh.volume(f > 100, iso=0.5)
    assert len(b.faces) == len(ref.faces)
    wide = np.zeros((24, 24, 48), np.uint8)
    wide[:, :, ::2] = f
    s = mint_mesh.volume(wide[:, :, ::2], iso=100)
    assert np.array_equal(s.vertices, ref.vertices)


def test_open_border_leaves_an_array_cut_by_its_border_open():
    f = np.zeros((8, 6, 7), np.float32)
    f[3:5] = 1.0
    closed = mint_mesh.volume(f, iso=0.5)
    assert mint_mesh.check(*closed)["watertight"]
    r = mint_mesh.volume(f, iso=0.5, open_border=True)
    c = mint_mesh.check(*r, no_weld=True)
    assert c["boundary_loops"] == 2 and c["non_manifold_edges"] == 0 and c["non_manifold_vertices"] == 0
    assert r.summary["volume"]["open_border"] is True
    assert r.summary["output_faces"] == len(r.faces) < len(closed.faces)


def test_volume_file_gives_the_cli_bytes_and_summary(mint_exe, tmp_path):
    src = tmp_path / "g.nhdr"
    mint_mesh.gen("volume", src, dims="40,36,30", spacing="0.8,0.8,1.25")
    s = mint_mesh.volume_file(src, tmp_path / "py.ply", iso=1000, threads=2)
    p = subprocess.run([mint_exe, "volume", str(src), str(tmp_path / "cli.ply"), "--iso", "1000", "--threads", "2", "--json"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    cli = json.loads(p.stdout)
    assert (tmp_path / "py.ply").read_bytes() == (tmp_path / "cli.ply").read_bytes()
    assert set(s) == set(cli) and s["output_faces"] == cli["output_faces"] > 0
    assert mint_mesh.check_file(tmp_path / "py.ply")["watertight"]


def test_volume_file_labels_one_surface_each(tmp_path):
    src = tmp_path / "l.nrrd"
    mint_mesh.gen("labels", src, dims="30,30,30")
    s = mint_mesh.volume_file(src, tmp_path / "l.ply", labels=True)
    assert len(s["labels"]) == 3
    for v in (1, 2, 3):
        assert mint_mesh.check_file(tmp_path / f"l.label-{v}.ply")["watertight"]
    one = mint_mesh.volume_file(src, tmp_path / "two.ply", labels=[1, 2], one_file=True)
    assert [x["volume"]["surface"] for x in one["labels"]] == ["label 1", "label 2"]


def test_a_shared_mr_volume_is_meshed_in_the_frame_its_header_declares(shared_data, tmp_path):
    s = mint_mesh.volume_file(shared_data / "volumes/mr-head-mhd-vtk/HeadMRVolume.mhd", tmp_path / "mr.ply", iso=60)
    assert s["volume"]["frame"] == "LPS (patient)" and s["volume"]["format"] == "MetaImage"
    assert mint_mesh.check_file(tmp_path / "mr.ply")["watertight"]


def test_bad_volume_arguments_raise_value_errors_naming_them(tmp_path):
    f = ball()
    cases = [
        (lambda: mint_mesh.volume(f[0], iso=0), "samples"),
        (lambda: mint_mesh.volume(np.zeros((0, 3, 3)), iso=0), "samples"),
        (lambda: mint_mesh.volume(f.astype(np.complex64), iso=0), "samples"),
        (lambda: mint_mesh.volume(f, iso=float("nan")), "iso"),
        (lambda: mint_mesh.volume(f, iso="high"), "iso"),
        (lambda: mint_mesh.volume(f, iso=0, spacing=(1, -1, 1)), "spacing"),
        (lambda: mint_mesh.volume(f, iso=0, origin=(0, 0)), "origin"),
        (lambda: mint_mesh.volume_file(tmp_path / "x.nrrd", tmp_path / "o.ply"), "iso="),
        (lambda: mint_mesh.volume_file(tmp_path / "x.nrrd", tmp_path / "o.ply", iso=1, labels=True), "iso="),
    ]
    for call, name in cases:
        with pytest.raises(ValueError, match=name):
            call()


def test_a_broken_volume_file_raises_the_cli_line_and_writes_nothing(mint_exe, tmp_path):
    (tmp_path / "short.raw").write_bytes(b"\0" * 100)
    hdr = tmp_path / "short.nhdr"
    hdr.write_text("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 5 5 5\nencoding: raw\ndata file: short.raw\n")
    with pytest.raises(mint_mesh.InputError) as e:
        mint_mesh.volume_file(hdr, tmp_path / "o.ply", iso=1)
    p = subprocess.run([mint_exe, "volume", str(hdr), str(tmp_path / "c.ply"), "--iso", "1"], capture_output=True, text=True)
    assert p.returncode != 0
    assert str(e.value) in p.stderr and "\n" not in str(e.value)
    assert not (tmp_path / "o.ply").exists()


def _other_series(b: bytes) -> bytes:
    """The file with the last digit of its SeriesInstanceUID changed."""
    i = b.index(bytes([0x20, 0x00, 0x0E, 0x00]) + b"UI")
    n = int.from_bytes(b[i + 6:i + 8], "little")
    v = bytearray(b[i + 8:i + 8 + n])
    k = max(j for j, c in enumerate(v) if chr(c).isdigit())
    v[k] = ord("0") if v[k] == ord("9") else v[k] + 1
    return b[:i + 8] + bytes(v) + b[i + 8 + n:]


def test_dicom_series_picks_one_series_of_a_folder(shared_data, tmp_path):
    src = shared_data / "volumes/ct-chest-dicom-series-lungpetctdx"
    study = tmp_path / "study"
    study.mkdir()
    for n in range(1, 6):
        b = (src / f"1-{n:02}.dcm").read_bytes()
        (study / f"1-{n:02}.dcm").write_bytes(b if n <= 2 else _other_series(b))
    with pytest.raises(mint_mesh.InputError, match="holds 2 series"):
        mint_mesh.volume_file(study, tmp_path / "o.ply", iso=300)
    assert not (tmp_path / "o.ply").exists()
    s = mint_mesh.volume_file(study, tmp_path / "o.ply", iso=300, dicom_series=2)
    assert s["volume"]["slices_read"] == 3
    s = mint_mesh.volume_file(study / "1-01.dcm", tmp_path / "o.ply", iso=300)
    assert s["volume"]["slices_read"] == 2
    with pytest.raises(mint_mesh.MintError, match="no series number 7"):
        mint_mesh.volume_file(study, tmp_path / "o.ply", iso=300, dicom_series=7)
