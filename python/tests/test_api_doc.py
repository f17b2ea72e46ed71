"""docs/python-api.md is what scripts/python_api_doc.py writes from the docstrings now: a changed
docstring or signature without a regenerated page fails here."""

import importlib.util
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_the_api_reference_page_is_current():
    spec = importlib.util.spec_from_file_location("python_api_doc", ROOT / "scripts" / "python_api_doc.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    page = (ROOT / "docs" / "python-api.md").read_text(encoding="utf-8")
    assert page == mod.render(), "docs/python-api.md is stale: run scripts/python_api_doc.py"
