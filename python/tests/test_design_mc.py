"""The Monte Carlo of a design's governing states on Dask (issue 24): the plan, the tables in
parts, the setup and one task per batch, merged equal to ``kappe design``'s
``reliability.monte_carlo`` with the same seed, bit for bit."""

import json
import subprocess

import pytest

import kappe

# Study No. 14's small cap (printed at 0.01 m/s, E(t) = 1.3 MPa + 400 Pa/s·t), every third state
# analysed, E₀ and γ uncertain, E₀ drifting −12 %/h: print P_f ≈ 2e-2 (the Rust tests' case).
DESIGN = """name = "mc"
[cap]
length = 0.15
[print]
path_sampling = 0.04
print_speed = 0.01
[robot]
enabled = false
[analysis]
row_stride = 8
states = "every:3"
[material.time]
model = "linear"
youngs_modulus = 1.3e6
youngs_modulus_rate = 400.0
[uncertainty]
"material.time.youngs_modulus" = { dist = "lognormal", cov = 0.15 }
"material.specific_weight" = { dist = "normal", cov = 0.05 }
monte_carlo = 3000
monte_carlo_method = "importance"
seed = 4
[uncertainty.drift]
"material.time.youngs_modulus" = { percent_per_hour = -12.0 }
"""


def comparable(mc):
    # The seconds are the run's, not the estimate's.
    return {k: v for k, v in mc.items() if k != "seconds"}


@pytest.fixture(scope="module")
def cli(tmp_path_factory, kappe_bin):
    d = tmp_path_factory.mktemp("design")
    f = d / "mc.toml"
    f.write_text(DESIGN)
    out = d / "out"
    subprocess.run([kappe_bin, "design", str(f), "--out", str(out), "-q", "--allow-fail"], check=True)
    return json.loads((out / "summary.json").read_text())["reliability"]["monte_carlo"]


def test_local_batches_equal_the_cli(cli):
    one = kappe.design_monte_carlo(DESIGN, 3000, seed=4, method="importance")
    three = kappe.design_monte_carlo(DESIGN, 3000, seed=4, method="importance", batches=3)
    assert comparable(one) == comparable(cli)
    assert comparable(three) == comparable(cli)
    assert cli["method"] == "importance" and 0.0 < cli["pf"] < 1.0


def test_dask_tasks_equal_the_local_run(cli):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster:
        with distributed.Client(cluster) as client:
            on_dask = kappe.design_monte_carlo(DESIGN, 3000, seed=4, method="importance", client=client, batches=5)
    assert comparable(on_dask) == comparable(cli)


def test_a_design_without_uncertainty_is_a_design_error():
    text = DESIGN.split("[uncertainty]")[0]
    with pytest.raises(kappe.DesignError) as e:
        kappe.design_monte_carlo(text, 1000)
    assert "uncertainty" in str(e.value)
