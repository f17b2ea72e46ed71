#!/usr/bin/env bash
# Builds the Python package `gearbif` (PyO3 extension, python/) into a virtual environment and runs
# its tests (python/tests, including the tutorial script docs/tutorial/theta25_diagram.py).
#
#   python/run_tests.sh [pytest arguments]
#
# The extension is built by `maturin develop` (dev profile) in the cargo target directory
# ($CARGO_TARGET_DIR, default target/); a rebuild is incremental. It cannot reuse the artifacts of
# `cargo test`: PyO3's proc macros unify other features of syn (so serde_derive, serde and every crate
# deriving serde get new hashes), so its first build compiles the core and its dependencies once more
# (without the CLI, plotting and diffsol). The venv lives in the target directory ($GEARBIF_VENV
# overrides it); Python packages come from PyPI: maturin, numpy, pytest, matplotlib.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
target="${CARGO_TARGET_DIR:-$root/target}"
venv="${GEARBIF_VENV:-$target/python-venv}"
python="${PYTHON:-python3}"
if [ ! -x "$venv/bin/python" ]; then
    "$python" -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check \
    "maturin>=1.9,<2" numpy pytest matplotlib
start=$(date +%s)
VIRTUAL_ENV="$venv" PATH="$venv/bin:$PATH" CARGO_TARGET_DIR="$target" \
    "$venv/bin/maturin" develop --manifest-path python/Cargo.toml
echo "== extension built in $(($(date +%s) - start)) s"
# the tests cross-check against the CLI binary that `cargo test` built in the same target directory
CARGO_TARGET_DIR="$target" "$venv/bin/python" -m pytest -q python/tests "$@"
