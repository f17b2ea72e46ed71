"""The tutorial script docs/tutorial/theta25_diagram.py runs (reduced range) and finds what the
continuation in Rust finds on the same range."""

import pathlib
import subprocess
import sys

import gearbif

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_theta25_tutorial_script_runs_and_plots(tmp_path):
    out = tmp_path / "theta25.png"
    r = subprocess.run(
        [sys.executable, str(ROOT / "docs" / "tutorial" / "theta25_diagram.py"), "--quick", "--out", str(out)],
        check=True, capture_output=True, text=True,
    )
    assert out.is_file() and out.stat().st_size > 10_000
    # the symmetry-breaking point it prints is the one the library locates on that range
    b = gearbif.continuation(gearbif.Gear.paper(25.0, 2.2), [2.98, 0.6], range=(2.2, 2.7), ds_max=0.05)
    sb = [s for s in b.specials if s.kind == "symmetry_breaking"][-1]
    assert f"f = {sb.param:.9f}" in r.stdout, r.stdout
    assert "asymmetric (P_T)" in r.stdout
