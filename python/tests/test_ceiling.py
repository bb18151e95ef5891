"""Issue 15: a ceiling from Python, here and one bay per Dask task, equals `kappe design ROOM.toml`."""

import json
import pathlib
import subprocess

import pytest

import kappe

# The three-bay room of the Rust ceiling tests, with buckling of every 4th state to keep it quick.
ROOM = (pathlib.Path(__file__).resolve().parents[2] / "crates/kappe/tests/data/small_room.toml").read_text() + (
    '\n[analysis]\nstates = "every:4"\n'
)


@pytest.fixture(scope="module")
def cli_room(tmp_path_factory: pytest.TempPathFactory, kappe_bin: str) -> pathlib.Path:
    tmp = tmp_path_factory.mktemp("room")
    (tmp / "room.toml").write_text(ROOM)
    o = subprocess.run(
        [kappe_bin, "design", "room.toml", "--out", "out", "--quiet", "--allow-fail"],
        cwd=tmp,
        capture_output=True,
        text=True,
    )
    assert o.returncode == 0, o.stderr
    return tmp / "out"


def _strip_timings(summary: dict) -> dict:
    # Wall-clock analysis timings differ between any two runs; everything else must be equal.
    summary.pop("analysis_timings_s", None)
    return summary


def _same_as_cli(r: "kappe.CeilingResult", out: pathlib.Path) -> None:
    assert r.summary == json.loads((out / "ceiling.json").read_text())
    assert r.index_html == (out / "index.html").read_text()
    files = dict(r.files)
    for n in range(1, 4):
        bay = out / f"bay_{n}"
        ours = _strip_timings(json.loads(files[f"bay_{n}/summary.json"]))
        assert ours == _strip_timings(json.loads((bay / "summary.json").read_text()))
        # Programs, trajectories and paths are byte for byte the CLI's.
        for p in sorted(bay.rglob("*")):
            name = f"bay_{n}/{p.relative_to(bay).as_posix()}"
            if p.is_file() and p.suffix in (".script", ".csv"):
                assert files[name] == p.read_bytes(), name
    assert {n for n, _ in r.files} == {
        p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file() and p.name != ".kappe-output.json"
    }


def test_ceiling_here_equals_the_cli(cli_room: pathlib.Path, tmp_path: pathlib.Path) -> None:
    r = kappe.ceiling(ROOM, allow_fail=True)
    assert len(r.bays) == 3
    _same_as_cli(r, cli_room)
    # write() follows the CLI's rule: it refuses a foreign directory, writes a new one.
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    with pytest.raises(ValueError, match="not a Kappe output"):
        r.write(str(tmp_path / "mine"))
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep"
    r.write(str(tmp_path / "room"))
    assert json.loads((tmp_path / "room" / "ceiling.json").read_text()) == r.summary


def test_ceiling_on_dask_equals_the_cli(cli_room: pathlib.Path) -> None:
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster:
        with distributed.Client(cluster) as client:
            r = kappe.ceiling(ROOM, client=client, allow_fail=True)
    _same_as_cli(r, cli_room)


def test_design_write_is_the_cli_output(tmp_path: pathlib.Path, kappe_bin: str) -> None:
    # The files of Result.write() come from the same library function as `kappe design`'s.
    cheap = kappe.Design({"cap": {"length": 0.05}, "print": {"layer_height": 0.015}})
    (tmp_path / "d.toml").write_text(cheap.to_toml())
    o = subprocess.run(
        [kappe_bin, "design", "d.toml", "--out", "cli", "--quiet", "--allow-fail", "--no-robot"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    assert o.returncode == 0, o.stderr
    r = kappe.design(cheap, robot=False, allow_fail=True)
    r.write(str(tmp_path / "py"))
    cli = sorted(p.relative_to(tmp_path / "cli").as_posix() for p in (tmp_path / "cli").rglob("*"))
    ours = sorted(p.relative_to(tmp_path / "py").as_posix() for p in (tmp_path / "py").rglob("*"))
    assert ours == cli
    for name in ("path.csv", "cap.obj", "network.json", "schedule.csv"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    # A second write replaces Kappe's own output; a user's file in it makes it refuse.
    r.write(str(tmp_path / "py"))
    (tmp_path / "py" / "mine.txt").write_text("keep")
    with pytest.raises(ValueError, match="did not write"):
        r.write(str(tmp_path / "py"))
    assert (tmp_path / "py" / "mine.txt").read_text() == "keep"
