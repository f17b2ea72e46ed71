"""gearbif.Model: the recorded gear of a model file (model.json) wherever a system is accepted.
The paper's model file (assets/paper_gear.model.json, base terms only) must give the paper's gear's
map, branch and classification; a malformed file raises RecordingError naming the file and the
field."""

import json
import os

import numpy as np
import pytest

import gearbif

ASSETS = os.path.join(os.path.dirname(__file__), "..", "..", "assets")


def paper_model(f):
    return gearbif.Model.load(os.path.join(ASSETS, "paper_gear.model.json"), f=f)


def test_load_and_parameters():
    m = paper_model(3.0)
    assert isinstance(m, gearbif.Model)
    assert m.f == 3.0 and m.period == pytest.approx(1 / 3)
    p = m.params
    assert p["g"] == pytest.approx(298.452035046191) and p["eta"] == 23.1 and p["drag_q"] == 0.0
    assert m.param_names == ["f", "g", "delta", "zeta", "eta"]
    assert m.with_param("drag_q", 0.01).params["drag_q"] == 0.01


def test_map_is_the_papers_gears():
    x = [np.radians(170.0), 18.85]
    a = gearbif.poincare_map(gearbif.Gear.paper(0.0, 3.0), x, section="half_period", tol=1e-11)
    b = gearbif.poincare_map(paper_model(3.0), x, section="half_period", tol=1e-11)
    np.testing.assert_allclose(b["x"], a["x"], rtol=1e-9)
    np.testing.assert_allclose(b["jac_x"], a["jac_x"], rtol=1e-7, atol=1e-9)


def test_continuation_in_a_parameter_of_the_lens():
    # η is a default column; drag_q is not: the continuation puts it into the active set
    gear, model = gearbif.Gear.paper(0.0, 3.0), paper_model(3.0)
    x = gearbif.simulate(gear, [0.0, 0.0], 100 * gear.period, samples_per_period=1)["x_end"]
    a = gearbif.continuation(gear, x, param="eta", range=(20.0, 26.0), max_steps=8)
    b = gearbif.continuation(model, x, param="eta", range=(20.0, 26.0), max_steps=8)
    assert isinstance(b.system, gearbif.Model) and len(a) == len(b)
    np.testing.assert_allclose(b.param, a.param, rtol=1e-8)
    np.testing.assert_allclose(b.x, a.x, rtol=1e-8, atol=1e-10)
    c = gearbif.continuation(model, x, param="drag_q", range=(0.0, 0.01), max_steps=4)
    assert c.param_name == "drag_q" and len(c) > 1


def test_bad_model_file_names_the_field(tmp_path):
    with open(os.path.join(ASSETS, "paper_gear.model.json")) as fh:
        doc = json.load(fh)
    doc["covariance"]["matrix"][0][0] = -4.0
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(doc))
    with pytest.raises(gearbif.RecordingError) as e:
        gearbif.Model.load(str(p))
    assert "covariance" in str(e.value) and "bad.json" in str(e.value)


def test_locate_gives_the_closed_forms_sigma(tmp_path):
    # the lock-loss fold f_c = (g - eta)/(2 pi zeta) of the paper's gear at Theta = 0 with a
    # covariance over (g, zeta, eta): sigma^2 = a^T C a, a = (1, -2 pi f_c, -1)/(2 pi zeta)
    with open(os.path.join(ASSETS, "paper_gear.model.json")) as fh:
        doc = json.load(fh)
    cov = [[4.0, 0.0, 1.0], [0.0, 4e-4, 0.0], [1.0, 0.0, 1.0]]
    doc["covariance"] = {"names": ["g", "zeta", "eta"], "matrix": cov}
    p = tmp_path / "cov.json"
    p.write_text(json.dumps(doc))
    m = gearbif.Model.load(str(p), f=39.7)
    assert m.covariance == (["g", "zeta", "eta"], cov)
    r = m.locate("fold", [1.5808, 250.3])
    g, zeta, eta = 298.452035046191, 1.1, 23.1
    fc = (g - eta) / (2 * np.pi * zeta)
    a = np.array([1.0, -2 * np.pi * fc, -1.0]) / (2 * np.pi * zeta)
    assert r["param"] == "f" and r["value"] == pytest.approx(fc, abs=1e-8)
    assert r["sigma"] == pytest.approx(np.sqrt(a @ np.array(cov) @ a), rel=1e-5)
    assert r["gradient"]["zeta"] == pytest.approx(a[1], rel=1e-5)
    # in eta: eta itself is not in sigma
    r = m.locate("fold", [1.5808, 250.3], param="eta")
    assert r["omitted"] == ["eta"] and r["value"] == pytest.approx(g - 2 * np.pi * zeta * 39.7, abs=1e-7)
    with pytest.raises(gearbif.GearbifError):
        m.locate("cusp", [1.5808, 250.3])
