"""Shared fixtures of the mint_mesh tests: small generated meshes, the
installed `mint` command, and the shared real data (../shared/data beside
the project root; its absence fails the tests that need it, never skips)."""

import os
import shutil
import sys
from pathlib import Path

import pytest

import mint_mesh

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data"


@pytest.fixture(scope="session")
def torus():
    """A 20,000-face torus (genus 1, closed), float64 / int64."""
    return mint_mesh.generate("torus", faces=20000)


@pytest.fixture(scope="session")
def sphere():
    """A 20,000-face UV sphere of radius 1."""
    return mint_mesh.generate("sphere", faces=20000)


@pytest.fixture(scope="session")
def mint_exe():
    """The `mint` command installed by the wheel (beside this Python)."""
    exe = Path(sys.executable).parent / "mint"
    if not exe.exists():
        found = shutil.which("mint")
        assert found, "the wheel's `mint` command is not installed"
        exe = Path(found)
    return str(exe)


@pytest.fixture(scope="session")
def shared_data():
    assert SHARED.is_dir(), f"{SHARED}: the shared real data is missing (it sits beside the project root)"
    return SHARED


@pytest.fixture
def quiet_env():
    env = dict(os.environ)
    env.pop("MINT_THREADS", None)
    return env
