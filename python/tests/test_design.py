import json
import math
import subprocess

import jsonschema
import numpy as np
import pytest
from conftest import CHEAP, ROOT

import kappe


def test_default_design_has_every_field_and_round_trips():
    d = kappe.Design()
    assert d["cap"]["span"] == 0.8 and d["cap"]["rise"] == 0.2
    assert kappe.Design.from_toml(d.to_toml()) == d
    assert kappe.Design(d.to_dict()) == d


def test_bad_fields_raise_design_error_naming_the_field():
    with pytest.raises(kappe.DesignError) as e:
        kappe.Design({"cap": {"tilt_deg": 95.0}})
    assert e.value.field == "cap.tilt_deg"
    assert "allowed" in str(e.value) or e.value.allowed
    # Wrong Python types: a string for a span, a NaN, a list of the wrong shape.
    with pytest.raises(kappe.DesignError) as e:
        kappe.Design({"cap": {"span": "wide"}})
    assert "cap.span" in str(e.value)
    with pytest.raises(kappe.DesignError) as e:
        kappe.Design({"cap": {"rise": float("nan")}})
    assert e.value.field == "cap.rise"
    with pytest.raises(kappe.DesignError) as e:
        kappe.Design({"cap": {"span": [1.0, 2.0]}})
    assert "cap.span" in str(e.value)
    with pytest.raises(kappe.DesignError) as e:
        kappe.Design({"cap": {"spam": 1.0}})
    assert "spam" in str(e.value)
    with pytest.raises(kappe.DesignError):
        kappe.Design({"cap": {"span": object()}})
    assert issubclass(kappe.DesignError, ValueError)


def test_design_equals_the_cli(tmp_path, kappe_bin):
    """Python design() of a design gives the numbers of `kappe design` exactly (same library,
    same options): states, BLF, stresses, mass."""
    d = kappe.Design(CHEAP)
    f = tmp_path / "d.toml"
    f.write_text(d.to_toml())
    out = tmp_path / "out"
    subprocess.run([kappe_bin, "design", str(f), "--out", str(out), "-q", "--allow-fail"], check=True)
    cli = json.loads((out / "summary.json").read_text())
    seen = []
    r = kappe.design(d, allow_fail=True, progress=lambda stage, done, total: seen.append(stage))
    py = r.summary
    for s in (cli, py):
        s.pop("analysis_timings_s", None)
    assert py == cli
    assert {"states", "analysis"} <= set(seen)
    assert r.ok == cli["ok"]
    assert len(r.states) == len(cli["states"])
    assert r.blf[-1] == cli["states"][-1]["blf"]
    assert isinstance(r.path.points, np.ndarray) and r.path.points.shape[1] == 3
    assert len(r.layers) == cli["counts"]["layers"]
    assert r.trajectory is not None and r.trajectory.shape[0] > 0
    assert r.report_html.startswith("<!DOCTYPE html>") or "<html" in r.report_html[:200]


def test_progress_can_stop_a_run():
    def stop(stage, done, total):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        kappe.design(kappe.Design(CHEAP), progress=stop, robot=False)


def test_analysis_options_are_checked():
    with pytest.raises(kappe.DesignError):
        kappe.design(kappe.Design(CHEAP), analysis={"states": "every:0"}, robot=False)
    r = kappe.design(kappe.Design(CHEAP), analysis=None, robot=False, report=False)
    assert all(s.get("blf") is None for s in r.states)
    assert math.isfinite(r.summary["mass_kg"])


def test_compas_round_trip(tmp_path):
    compas = pytest.importorskip("compas")
    import compas.data  # noqa: F401, F811  (registers the data classes)

    d = kappe.Design(CHEAP)
    path = tmp_path / "d.json"
    compas.json_dump(d, str(path))
    back = compas.json_load(str(path))
    assert isinstance(back, kappe.Design) and back == d
    r = kappe.design(d, analysis=None, robot=False, report=False)
    compas.json_dump(r, str(tmp_path / "r.json"))
    back = compas.json_load(str(tmp_path / "r.json"))
    assert isinstance(back, kappe.Result) and back.summary == r.summary


def test_default_designs_summary_matches_its_published_schema(tmp_path, kappe_bin):
    """Issue 22: summary.json of the default design (`kappe design`, robot and every state)
    validates against docs/formats/summary.schema.json, the schema generated from the typed
    summary; an output missing a required field or with a wrong type would fail here."""
    schema = json.loads((ROOT / "docs" / "formats" / "summary.schema.json").read_text())
    out = tmp_path / "out"
    subprocess.run([kappe_bin, "design", "--out", str(out), "-q", "--allow-fail"], check=True)
    summary = json.loads((out / "summary.json").read_text())
    jsonschema.validate(summary, schema)
    # The check can fail: a summary without its verdict does not validate.
    del summary["ok"]
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(summary, schema)
