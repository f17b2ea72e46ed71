#!/usr/bin/env bash
# Builds the Python package `gearbif` (PyO3 extension, python/) and runs its tests (python/tests,
# including the tutorial script docs/tutorial/theta25_diagram.py) in a virtual environment.
#
#   python/run_tests.sh [pytest arguments]
#
# The extension is built by cargo in the cargo target directory ($CARGO_TARGET_DIR, default
# target/), in one of two ways ($GEARBIF_PY_BUILD):
#
# - `workspace` (default): the package selection, features and profile of the README's test
#   command `cargo test --workspace --all-features`, so after that command every compiled
#   dependency is shared and only PyO3, numpy (the crate), ndarray and the bindings are compiled
#   here (36–59 s on 2 cores in `.ci/run` on a clean clone, against 201 s for `alone`).
# - `alone`: the bindings' own package selection (what `maturin develop` builds; dev profile; the
#   core without its CLI, plotting and diffsol features). PyO3's proc macros turn on other
#   features of syn than `cargo test` does, hence new builds of serde_derive, serde and every
#   crate deriving serde: the core and its dependencies are compiled a second time next to the
#   artifacts of `cargo test`.
#
# The built library is loaded from $target/python-ext; the venv lives in the target directory
# ($GEARBIF_VENV overrides it) and gets numpy, pytest, matplotlib and pandas from PyPI. `pip install .`
# (maturin) is the way to install the package; this script is the test loop.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
target="${CARGO_TARGET_DIR:-$root/target}"
venv="${GEARBIF_VENV:-$target/python-venv}"
python="${PYTHON:-python3}"
if [ ! -x "$venv/bin/python" ]; then
    "$python" -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check numpy pytest matplotlib pandas
start=$(date +%s)
export PYO3_PYTHON="$venv/bin/python" PYO3_BUILD_EXTENSION_MODULE=1 CARGO_TARGET_DIR="$target"
case "${GEARBIF_PY_BUILD:-workspace}" in
    # --examples activates the dev-dependencies as `cargo test` does (their features are unified too)
    workspace) cargo build --workspace --all-features --profile test --lib --examples ;;
    alone) cargo build --manifest-path python/Cargo.toml --lib ;;
    *) echo "GEARBIF_PY_BUILD must be alone or workspace" >&2; exit 2 ;;
esac
# the package as maturin lays it out: python/gearbif/ (Python sources, stubs) with the extension
# inside as gearbif/_core<suffix>; assembled beside the old one and swapped in
ext="$target/python-ext"
mkdir -p "$ext"
rm -rf "$ext/gearbif.new" "$ext/gearbif.old"
cp -r python/gearbif "$ext/gearbif.new"
suffix="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_config_var("EXT_SUFFIX"))')"
cp "$target/debug/libgearbif_py.so" "$ext/gearbif.new/_core$suffix"
rm -f "$ext"/gearbif.*.so
if [ -d "$ext/gearbif" ]; then mv "$ext/gearbif" "$ext/gearbif.old"; fi
mv "$ext/gearbif.new" "$ext/gearbif"
rm -rf "$ext/gearbif.old"
echo "== extension built in $(($(date +%s) - start)) s"
# the tests cross-check against the CLI binary that `cargo test` built in the same target directory
PYTHONPATH="$ext${PYTHONPATH:+:$PYTHONPATH}" "$venv/bin/python" -m pytest -q python/tests "$@"
