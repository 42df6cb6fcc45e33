#!/usr/bin/env bash
# Every test: the Rust workspace, then the Python package (built as a wheel
# into a virtual environment of its own, with its test dependencies, and its
# pytest suite run against the installed package). The README's test command.
set -euo pipefail
cd "$(dirname "$0")/.."
# The extension module (python/) is built by maturin, not linked as a test.
cargo test --release --workspace --exclude mint-python
bash scripts/python-tests.sh
