import json
import subprocess

import numpy as np
import pytest
from conftest import FIXTURES

import kappe


def test_cem_fixture_equals_the_cli(tmp_path, kappe_bin):
    src = FIXTURES / "cem" / "arch2d_crown.input.json"
    topo = json.loads(src.read_text())
    py = kappe.cem.solve(topo)
    out = tmp_path / "eq.json"
    subprocess.run([kappe_bin, "cem", "solve", str(src), "-o", str(out)], check=True)
    assert py == json.loads(out.read_text())


def test_cem_bad_topology_is_a_clear_error():
    with pytest.raises(ValueError):
        kappe.cem.solve({"nodes": "x"})
    with pytest.raises(TypeError):
        kappe.cem.solve(42)


def test_fe_buckle_plate():
    mesh = json.loads((FIXTURES / "fe" / "plate_ss_s3_n16.mesh.json").read_text())
    r = kappe.fe.buckle(mesh, modes=2)
    assert r["factors"].shape == (2,) and np.all(r["factors"] > 0)
    with pytest.raises(ValueError):
        kappe.fe.buckle(mesh, modes=0)


def test_fe_buckle_equals_the_cli(tmp_path, kappe_bin):
    src = FIXTURES / "fe" / "plate_ss_s3_n16.mesh.json"
    out = tmp_path / "b.json"
    subprocess.run([kappe_bin, "fe", "buckle", str(src), "--modes", "2", "--mode-shapes", "-o", str(out)], check=True)
    cli = json.loads(out.read_text())
    py = kappe.fe.buckle(json.loads(src.read_text()), modes=2)
    # The same library call on the same model: the numbers are equal, not close (the CLI's
    # JSON prints shortest round-trip floats). Wall-clock times differ.
    assert py["factors"].tolist() == cli["factors"]
    assert [m.tolist() for m in py["modes"]] == cli["modes"]
    for key in ("static", "dofs", "residuals", "mesh_quality", "sturm"):
        assert py[key] == cli[key], key
    assert py["solver"]["element_kind"] == cli["solver"]["element_kind"]


def test_fe_static_equals_the_cli(tmp_path, kappe_bin):
    src = FIXTURES / "fe" / "plate_ss_s3_n16.mesh.json"
    out = tmp_path / "s.json"
    subprocess.run([kappe_bin, "fe", "static", str(src), "-o", str(out)], check=True)
    cli = json.loads(out.read_text())
    py = kappe.fe.static(json.loads(src.read_text()))
    # The same library call: equal numbers (shortest round-trip floats in the CLI's JSON).
    assert py["displacements"].shape == (len(cli["displacements"]), 6)
    assert py["displacements"].tolist() == cli["displacements"]
    for key in ("static", "dofs", "element", "mesh_quality", "reactions", "elements"):
        assert py[key] == cli[key], key


def test_robot_ik_solutions_reach_the_pose():
    pose = np.eye(4)
    pose[:3, 3] = [0.6, 0.2, 0.4]
    pose[:3, :3] = np.diag([1.0, -1.0, -1.0])
    sols = kappe.robot.ik(pose)
    assert sols.ndim == 2 and sols.shape[1] == 6 and len(sols) >= 1
    with pytest.raises(ValueError):
        kappe.robot.ik(np.eye(3))


def test_prepared_topology_equals_the_json_solve():
    topo = json.loads((FIXTURES / "cem" / "arch2d_crown.input.json").read_text())
    full = kappe.cem.solve(topo)
    fast = kappe.cem.Topology(topo).solve()
    xyz = np.asarray([n["xyz"] for n in full["nodes"]], dtype=float)
    # Same solve, same numbers: the JSON writer prints shortest round-trip floats.
    assert np.array_equal(fast["xyz"], xyz)
