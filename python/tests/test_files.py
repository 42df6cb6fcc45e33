"""The file calls: the same bytes and summaries as the `mint` command the
wheel installs, typed errors with the CLI's one-line messages, progress
callbacks, cancellation, and Ctrl-C."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import mint_mesh


def run_cli(mint_exe, *args):
    p = subprocess.run([mint_exe, *map(str, args)], capture_output=True, text=True)
    return p


def test_the_wheels_mint_command_passes_the_smoke_test(mint_exe, tmp_path):
    p = subprocess.run([mint_exe, "demo"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert "demo ok" in p.stdout + p.stderr and (tmp_path / "mint-demo.png").exists()
    assert run_cli(mint_exe, "--version").stdout.startswith("mint ")


def test_file_calls_give_the_cli_bytes_and_summary(mint_exe, tmp_path):
    scan = tmp_path / "scan.ply"
    g = mint_mesh.gen("scan", scan, faces=200000, seed=3)
    assert g["holes"] > 0 and g["flipped_faces"] > 0  # its defect list
    s = mint_mesh.resample_file(scan, tmp_path / "py.ply", cells=300000, mem="256M", threads=2)
    p = run_cli(mint_exe, "resample", scan, tmp_path / "cli.ply", "--cells", 300000, "--mem", "256M", "--threads", 2, "--json")
    assert p.returncode == 0, p.stderr
    cli = json.loads(p.stdout)
    assert (tmp_path / "py.ply").read_bytes() == (tmp_path / "cli.ply").read_bytes()
    assert set(s) == set(cli)
    for k in ("output_faces", "output_vertices", "grid_cells", "cell_size", "input_faces"):
        assert s[k] == cli[k], k
    # Staged and split: the same bytes again.
    s2 = mint_mesh.resample_file([scan], tmp_path / "parts.ply", cells=300000, work=tmp_path / "work", parts=3, slabs=4)
    assert (tmp_path / "parts.ply").read_bytes() == (tmp_path / "cli.ply").read_bytes()
    assert s2["output_faces"] == cli["output_faces"]

    d = mint_mesh.decimate_file(scan, tmp_path / "d-py.ply", target_faces=5000)
    assert run_cli(mint_exe, "decimate", scan, tmp_path / "d-cli.ply", "--faces", 5000, "--quiet").returncode == 0
    assert (tmp_path / "d-py.ply").read_bytes() == (tmp_path / "d-cli.ply").read_bytes()
    assert d["output_faces"] == len(mint_mesh.read(tmp_path / "d-py.ply").faces)

    c = mint_mesh.check_file(tmp_path / "py.ply")
    assert c == json.loads(run_cli(mint_exe, "check", tmp_path / "py.ply", "--json").stdout)
    assert c["watertight"]

    r = mint_mesh.render_file([scan, tmp_path / "py.ply"], tmp_path / "py.png", size="300x200")
    assert run_cli(mint_exe, "render", scan, tmp_path / "py.ply", tmp_path / "cli.png", "--size", "300x200", "--quiet").returncode == 0
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    assert r["width"] >= 300 if "width" in r else True

    mint_mesh.convert(tmp_path / "py.ply", tmp_path / "py.obj")
    assert run_cli(mint_exe, "convert", tmp_path / "py.ply", tmp_path / "cli.obj", "--quiet").returncode == 0
    assert (tmp_path / "py.obj").read_bytes() == (tmp_path / "cli.obj").read_bytes()

    dist = mint_mesh.distance_file(scan, tmp_path / "py.ply", samples=20000)
    assert dist == json.loads(run_cli(mint_exe, "distance", scan, tmp_path / "py.ply", "--samples", 20000, "--json").stdout)


def test_real_scan_from_the_shared_data(shared_data, tmp_path):
    horse = shared_data / "cyberware_horse_mesh" / "horse.ply"
    s = mint_mesh.decimate_file(horse, tmp_path / "horse.ply", target_faces=10000)
    assert abs(s["output_faces"] - 10000) <= 200
    v, f = mint_mesh.read(tmp_path / "horse.ply")
    assert mint_mesh.check(v, f)["watertight"]


def test_errors_are_typed_with_the_cli_message(mint_exe, tmp_path):
    missing = tmp_path / "missing.ply"
    with pytest.raises(mint_mesh.MintIOError) as e:
        mint_mesh.resample_file(missing, tmp_path / "o.ply", cells=1000)
    assert isinstance(e.value, OSError) and isinstance(e.value, mint_mesh.MintError)
    cli = run_cli(mint_exe, "resample", missing, tmp_path / "o.ply", "--cells", 1000)
    assert cli.returncode == 1 and cli.stderr.strip() == f"mint: error: {e.value}"

    bad = tmp_path / "bad.ply"
    bad.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n" + b"\0" * 20)
    with pytest.raises(mint_mesh.InputError) as e:
        mint_mesh.resample_file(bad, tmp_path / "o.ply", cells=1000)
    assert str(bad) in str(e.value) and "\n" not in str(e.value)
    assert not (tmp_path / "o.ply").exists()

    textured = tmp_path / "t.obj"
    (tmp_path / "t.mtl").write_text("newmtl m\nmap_Kd big.png\n")
    import zlib, struct

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    w = h = 8000  # 244 MiB decoded, more than a 64M budget gives textures
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) + chunk(b"IDAT", zlib.compress(b"")) + chunk(b"IEND", b"")
    (tmp_path / "big.png").write_bytes(png)
    textured.write_text("mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 3/3 2/2\nf 1/1 2/2 4/3\nf 1/1 4/3 3/3\nf 2/2 3/3 4/1\n")
    with pytest.raises(mint_mesh.BudgetError, match="give --mem"):
        mint_mesh.resample_file(textured, tmp_path / "o.ply", cells=1000, mem="64M")


def test_progress_callback_sees_phases(tmp_path):
    scan = tmp_path / "s.ply"
    mint_mesh.gen("sphere", scan, faces=400000)
    calls = []
    mint_mesh.resample_file(scan, tmp_path / "o.ply", cells=2000000, progress=lambda *a: calls.append(a))
    phases = [c[0] for c in calls]
    assert {"bounds", "discretize", "reconstruct"} <= set(phases), set(phases)
    for phase, done, total in calls:
        assert isinstance(phase, str) and done >= 0 and total >= 0 and (total == 0 or done <= total)
    # Each phase ends complete.
    last = {}
    for phase, done, total in calls:
        last[phase] = (done, total)
    assert all(d == t for d, t in last.values() if t > 0)
    # The array calls report too.
    seen = []
    mint_mesh.resample(*mint_mesh.read(scan), cells=200000, progress=lambda p, d, t: seen.append(p))
    assert "discretize" in seen


def test_progress_callback_can_stop_the_run(tmp_path):
    scan = tmp_path / "s.ply"
    mint_mesh.gen("sphere", scan, faces=400000)
    with pytest.raises(mint_mesh.CancelledError, match="stopped by the progress callback"):
        mint_mesh.resample_file(scan, tmp_path / "o.ply", cells=2000000, progress=lambda p, d, t: p != "discretize")
    assert sorted(os.listdir(tmp_path)) == ["s.ply"]

    class Boom(Exception):
        pass

    def boom(p, d, t):
        raise Boom(p)

    with pytest.raises(Boom):
        mint_mesh.resample_file(scan, tmp_path / "o.ply", cells=2000000, progress=boom)
    assert sorted(os.listdir(tmp_path)) == ["s.ply"]


def test_warnings_become_python_warnings(tmp_path, torus):
    mint_mesh.write(tmp_path / "c.ply", *torus, colors=np.full((len(torus[0]), 3), 7, np.uint8))
    with pytest.warns(mint_mesh.MintWarning, match="cannot hold per-vertex colour"):
        mint_mesh.convert(tmp_path / "c.ply", tmp_path / "c.stl")


CTRL_C = textwrap.dedent("""
    import signal, sys, time, mint_mesh
    # Python's own Ctrl-C handler, even when this test runs in a background
    # job (whose children start with SIGINT ignored, so Python installs none).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    said = []

    def running(phase, done, total):
        # Says once that the run is under way; the parent then sends SIGINT.
        if not said:
            said.append(phase)
            print("running", phase, flush=True)
        return True

    try:
        mint_mesh.resample_file(sys.argv[1], sys.argv[2], cells=int(sys.argv[4]), mem="512M", tmp=sys.argv[3],
                                progress=running)
    except KeyboardInterrupt:
        print("interrupted", time.time(), flush=True)
        sys.exit(7)
    print("finished", flush=True)
""")


def test_ctrl_c_raises_keyboard_interrupt_quickly_and_leaves_nothing(tmp_path):
    src = tmp_path / "in"
    out = tmp_path / "out"
    scratch = tmp_path / "scratch"
    for d in (src, out, scratch):
        d.mkdir()
    mint_mesh.gen("sphere", src / "s.ply", faces=2000000)
    # A 2-billion-cell grid takes seconds even on a fast machine; the signal
    # is sent as soon as the child reports its first progress, not after a
    # fixed sleep (a fast machine finished a 400M-cell run inside one).
    p = subprocess.Popen([sys.executable, "-c", CTRL_C, str(src / "s.ply"), str(out / "o.ply"), str(scratch),
                          "2000000000"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = p.stdout.readline().split()
    assert line[:1] == ["running"], (line, p.stderr.read())
    sent = time.time()
    p.send_signal(signal.SIGINT)
    stdout, stderr = p.communicate(timeout=30)
    assert p.returncode == 7, (stdout, stderr)
    when = float(stdout.split()[1])
    assert when - sent < 1.0, f"KeyboardInterrupt {when - sent:.2f} s after the signal"
    assert os.listdir(out) == [] and os.listdir(scratch) == []


def test_long_calls_release_the_gil_and_run_side_by_side(tmp_path):
    import threading

    scan = tmp_path / "s.ply"
    mint_mesh.gen("sphere", scan, faces=400000)
    results = {}

    def work(name):
        results[name] = mint_mesh.resample_file(scan, tmp_path / f"{name}.ply", cells=3000000, threads=1)

    threads = [threading.Thread(target=work, args=(n,)) for n in ("a", "b")]
    for t in threads:
        t.start()
    ticks = 0
    while any(t.is_alive() for t in threads):
        ticks += 1  # Python keeps running here while mint works
        time.sleep(0.001)
    for t in threads:
        t.join()
    assert ticks > 20, f"the main thread ran only {ticks} times during the runs"
    assert (tmp_path / "a.ply").read_bytes() == (tmp_path / "b.ply").read_bytes()
    assert results["a"]["output_faces"] == results["b"]["output_faces"] > 0
