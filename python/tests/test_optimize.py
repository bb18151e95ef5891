import json
import subprocess

import pytest
from conftest import FIXTURES

import kappe

# Four evaluations of a cheap cap (3 centre layers of 15 mm; buckling of the last state only):
# a second; the start section's 20-25 mm overhang fails l_o,max = 10 mm, so the loop ends
# infeasible and names the binding constraint.
OPTIMIZE = """design = { cap = { span = 0.8, rise = 0.2, length = 0.05 }, print = { layer_height = 0.015 } }
max_evaluations = 4
[free]
"cap.rise" = { min = 0.15, max = 0.25 }
[analysis]
states = "every:1000"
[verify]
states = "every:1000"
"""


def without_timings(value):
    """optimize.json without the wall-clock times of the verification analysis."""
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items() if k not in ("timings", "fe_seconds")}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


def test_optimize_equals_the_cli(tmp_path, kappe_bin):
    f = tmp_path / "opt.toml"
    f.write_text(OPTIMIZE)
    out = tmp_path / "out"
    cli = subprocess.run([kappe_bin, "optimize", str(f), "--out", str(out)], capture_output=True, text=True)
    assert cli.returncode == 1, cli.stderr  # infeasible: status 1
    seen = []
    r = kappe.optimize(str(f), progress=seen.append)
    assert not r.feasible
    # Every evaluation was reported as it happened (`accepted` is decided after the report).
    done = r.document["result"]["evaluations"]
    assert [(e["evaluation"], e["parameters"]) for e in seen] == [(e["evaluation"], e["parameters"]) for e in done]
    assert r.design_toml == (out / "design.toml").read_text()
    assert without_timings(r.document) == without_timings(json.loads((out / "optimize.json").read_text()))
    # The command prints the per-evaluation table, then the report, then where it wrote.
    assert r.report in cli.stdout
    assert "overhang_max" in r.report
    with pytest.raises(ValueError):
        kappe.optimize(str(f), max_evaluations=0)

    def stop(evaluation):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        kappe.optimize(str(f), progress=stop)
    with pytest.raises(kappe.DesignError):
        kappe.optimize('[free]\n"cap.spam" = { min = 0.1, max = 0.2 }\n')


def test_cem_optimize_equals_the_cli(tmp_path, kappe_bin):
    src = FIXTURES / "cem" / "opt_arch_span_rise.input.json"
    out = tmp_path / "opt.json"
    cli = subprocess.run([kappe_bin, "cem", "optimize", str(src), "-o", str(out)], capture_output=True, text=True)
    assert cli.returncode == 0, cli.stderr
    py = kappe.cem.optimize(json.loads(src.read_text()))
    assert py["equilibrium"] == json.loads(out.read_text())
    assert py["report"] == cli.stderr
    assert py["converged"]
