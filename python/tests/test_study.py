import json
import subprocess

import pytest

import kappe

STUDY = """title = "four"
[base]
cap.length = 0.05
print.layer_height = 0.015
[analysis]
states = "every:1000"
[grid]
"constraints.overhang_max" = [0.01, 0.03]
"constraints.sigma_min" = [-12e3, -40e3]
"""


def cli_rows(tmp_path, kappe_bin):
    f = tmp_path / "s.toml"
    f.write_text(STUDY)
    subprocess.run([kappe_bin, "study", str(f), "--out", str(tmp_path / "cli"), "-q", "--no-robot"])
    return (tmp_path / "cli" / "study.json").read_text(), (tmp_path / "cli" / "study.csv").read_text()


def test_local_study_equals_the_cli(tmp_path, kappe_bin):
    cli_json, cli_csv = cli_rows(tmp_path, kappe_bin)
    r = kappe.study(str(tmp_path / "s.toml"), no_robot=True)
    assert r.csv == cli_csv
    assert json.loads(r.json)["rows"] == json.loads(cli_json)["rows"]
    assert len(r.rows) == 4


def test_written_study_equals_the_cli_output(tmp_path, kappe_bin):
    cli_rows(tmp_path, kappe_bin)
    r = kappe.study(str(tmp_path / "s.toml"), no_robot=True)
    r.write(str(tmp_path / "py"))

    def tree(root):
        # `.kappe-output.json` is Kappe's manifest of its outputs: it names the command.
        return {
            p.relative_to(root).as_posix(): p.read_bytes()
            for p in root.rglob("*")
            if p.is_file() and p.name != ".kappe-output.json"
        }

    cli, py = tree(tmp_path / "cli"), tree(tmp_path / "py")
    assert sorted(py) == sorted(cli)
    for name, data in cli.items():
        if name.endswith("summary.json"):
            # The wall-clock analysis timings differ between two runs; the rest is equal.
            a, b = json.loads(data), json.loads(py[name])
            a.pop("analysis_timings_s", None)
            b.pop("analysis_timings_s", None)
            assert a == b, name
        else:
            assert py[name] == data, name


def test_dask_study_equals_the_cli(tmp_path, kappe_bin):
    distributed = pytest.importorskip("distributed")
    cli_json, cli_csv = cli_rows(tmp_path, kappe_bin)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster:
        with distributed.Client(cluster) as client:
            r = kappe.study(str(tmp_path / "s.toml"), client=client, no_robot=True)
    assert r.csv == cli_csv
    assert json.loads(r.json)["rows"] == json.loads(cli_json)["rows"]


def test_bad_study_is_a_design_error():
    with pytest.raises(kappe.DesignError) as e:
        kappe.study('[grid]\n"cap.spam" = [1.0]\n')
    assert "cap.spam" in str(e.value)
