"""The tutorial's Python: the script docs/tutorial/theta25_diagram.py runs (reduced range) and
finds what the continuation in Rust finds on the same range; the quick Python blocks of
docs/tutorial.md print what the page shows (scripts/check_tutorial.py), and a number changed on the
page fails that check."""

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


def check_python_blocks(page):
    return subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "check_tutorial.py"), "--python", sys.executable, "--quick",
         "--page", str(page)],
        capture_output=True, text=True,
    )


def test_the_quick_python_blocks_print_what_the_page_shows():
    r = check_python_blocks(ROOT / "docs" / "tutorial.md")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "python:" in r.stdout and "checked blocks agree" in r.stdout


def test_a_number_changed_in_a_python_block_fails_the_check(tmp_path):
    page = (ROOT / "docs" / "tutorial.md").read_text()
    line = "  Θ = 10.0000°  f_c = 37.886528745 Hz"
    assert line in page, "the tutorial's boundary block has moved: update this test"
    bad = tmp_path / "tutorial.md"
    bad.write_text(page.replace(line, "  Θ = 10.0000°  f_c = 37.886538745 Hz", 1))
    r = check_python_blocks(bad)
    assert r.returncode == 1 and "page 37.886538745" in r.stdout, r.stdout + r.stderr
