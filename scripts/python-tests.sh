#!/usr/bin/env bash
# Builds the Python wheel (PyO3 + maturin, fetched by pip as the build
# requirement) into a fresh virtual environment under target/, installs its
# test dependencies (pytest, trimesh) and runs python/tests against the
# installed package, as a user's `pip install ./python` would give it.
# PYTHON chooses the interpreter (default python3); MINT_PY_VENV the venv.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
VENV=${MINT_PY_VENV:-target/py-venv}
rm -rf "$VENV"
if ! "$PY" -m venv "$VENV" 2>/dev/null; then
    # Debian's python3 without python3-venv: virtualenv from PyPI instead.
    rm -rf "$VENV"
    "$PY" -m pip install --quiet --user virtualenv || "$PY" -m pip install --quiet --user --break-system-packages virtualenv
    "$PY" -m virtualenv --quiet "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --upgrade pip
"$VENV/bin/python" -m pip install --quiet "./python[test]"
# From the repository root with importlib imports, so that python/mint_mesh
# (the sources, without the compiled module) cannot shadow the installed package.
"$VENV/bin/python" -m pytest -q -p no:cacheprovider --import-mode=importlib python/tests "$@"
