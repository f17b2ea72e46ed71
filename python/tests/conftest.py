"""Shared fixtures: the command-line binary (for cross-checks against the Rust CLI)."""

import os
import pathlib
import shutil
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _target_dir() -> pathlib.Path:
    return pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))


@pytest.fixture(scope="session")
def gearbif_cli() -> str:
    """Path of the `gearbif` binary: $GEARBIF_BIN, else the one `cargo test` built in the target
    directory, else built here with cargo."""
    explicit = os.environ.get("GEARBIF_BIN")
    if explicit:
        return explicit
    built = _target_dir() / "debug" / "gearbif"
    if built.is_file():
        return str(built)
    cargo = shutil.which("cargo")
    if cargo is None:
        pytest.fail("no gearbif binary: set GEARBIF_BIN or install cargo")
    subprocess.run([cargo, "build", "--bin", "gearbif"], cwd=ROOT, check=True)
    return str(built)
