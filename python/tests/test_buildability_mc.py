"""The print's Monte Carlo of a buildability spec on Dask (issue 24): one task per batch, the
merged result equal to the local run with the same seed (and to ``kappe buildability``)."""

import json
import subprocess

import pytest

import kappe

SCATTER = """
[uncertainty]
"material.time.youngs_modulus" = { dist = "lognormal", cov = 0.15 }
"material.time.youngs_modulus_rate" = { dist = "lognormal", cov = 0.15 }
"material.time.compressive_strength" = { dist = "lognormal", cov = 0.10 }
"material.time.compressive_strength_rate" = { dist = "lognormal", cov = 0.10 }
"material.specific_weight" = { dist = "normal", cov = 0.02 }
"process.layer_time" = { dist = "lognormal", cov = 0.05 }
seed = 5
monte_carlo = 3000
"""


@pytest.fixture(scope="module")
def spec(tmp_path_factory, kappe_bin):
    """The example cylinder (``kappe init --kind buildability``), 12 layers of 24 segments, its
    strength lowered to 2300 Pa so the top layer counts fail now and then, with the scatter of
    the Rust tests' fixture."""
    d = tmp_path_factory.mktemp("spec")
    f = d / "c.toml"
    subprocess.run([kappe_bin, "init", str(f), "--kind", "buildability"], check=True, capture_output=True)
    text = (
        f.read_text()
        .replace("max_layers = 60 ", "max_layers = 12 ")
        .replace("# segments = 48 ", "segments = 24 ")
        .replace("compressive_strength = 5984.0", "compressive_strength = 2300.0")
        .replace("stop_at_failure = true", "stop_at_failure = false")
    )
    f.write_text(text + SCATTER)
    return f


def comparable(mc):
    # The wall-clock seconds and the fallback count are the run's, not the estimate's.
    return {k: v for k, v in mc.items() if k not in ("seconds", "resolves")}


def test_local_batches_equal_the_cli(tmp_path, spec, kappe_bin):
    out = tmp_path / "out"
    subprocess.run([kappe_bin, "buildability", str(spec), "--out", str(out), "--quiet"], check=True)
    cli = json.loads((out / "buildability.json").read_text())["result"]["monte_carlo"]
    one = kappe.buildability_monte_carlo(spec, 3000, seed=5)
    three = kappe.buildability_monte_carlo(spec, 3000, seed=5, batches=3)
    assert comparable(one) == comparable(cli)
    assert comparable(three) == comparable(cli)
    assert 0.0 < one["pf"] < 1.0


def test_dask_batches_equal_the_local_run(spec):
    distributed = pytest.importorskip("distributed")
    local = kappe.buildability_monte_carlo(spec, 3000, seed=5)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster:
        with distributed.Client(cluster) as client:
            on_dask = kappe.buildability_monte_carlo(spec, 3000, seed=5, client=client, batches=5)
    assert comparable(on_dask) == comparable(local)


NONLINEAR = """
[analysis.nonlinear]

[uncertainty]
"analysis.nonlinear.imperfection" = { dist = "lognormal", cov = 0.5 }
"material.time.youngs_modulus" = { dist = "lognormal", cov = 0.15 }
"material.specific_weight" = { dist = "normal", cov = 0.02 }
seed = 2
monte_carlo = 2000
"""


def test_the_collapse_is_sampled_locally_and_on_dask_as_by_the_cli(tmp_path, spec, kappe_bin):
    # With [analysis.nonlinear] and the imperfection uncertain, the collapse is a limit state of
    # every tabulated layer count: the Python run (collapse tables built from the deterministic
    # states, as the CLI builds them) and the Dask run (the collapse tables one more task,
    # shipped with the linear tables) equal `kappe buildability`'s Monte Carlo.
    distributed = pytest.importorskip("distributed")
    f = tmp_path / "nonlinear.toml"
    f.write_text(spec.read_text().split("[uncertainty]")[0] + NONLINEAR)
    out = tmp_path / "out"
    subprocess.run([kappe_bin, "buildability", str(f), "--out", str(out), "--quiet"], check=True)
    result = json.loads((out / "buildability.json").read_text())["result"]
    assert result["collapse_reliability"]["states"], "some layer count has a collapse table"
    cli = result["monte_carlo"]
    local = kappe.buildability_monte_carlo(f, 2000, seed=2)
    assert comparable(local) == comparable(cli)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster:
        with distributed.Client(cluster) as client:
            on_dask = kappe.buildability_monte_carlo(f, 2000, seed=2, client=client, batches=3)
    assert comparable(on_dask) == comparable(cli)


def test_a_spec_without_uncertainty_is_a_design_error(spec):
    text = spec.read_text().split("[uncertainty]")[0]
    with pytest.raises(kappe.DesignError) as e:
        kappe.buildability_monte_carlo(text, 1000)
    assert "uncertainty" in str(e.value)
