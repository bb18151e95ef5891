"""Issue 28, defect 7: file arguments accept a path (str or os.PathLike), a missing file is
reported as a missing file (not parsed as TOML text), and refusals speak Python (force=True)."""

import pytest

import kappe


@pytest.mark.parametrize("run", [kappe.study, kappe.ceiling, kappe.optimize])
def test_a_missing_file_is_reported_as_missing(tmp_path, run):
    missing = tmp_path / "no_such.toml"
    for arg in (str(missing), missing):
        with pytest.raises(FileNotFoundError) as e:
            run(arg)
        assert "no_such.toml" in str(e.value)
        assert "no such file" in str(e.value)


def test_a_path_object_is_read_as_the_file(tmp_path):
    # A ceiling file whose bay list is empty: the error must come from reading the file's
    # contents, which shows that the pathlib.Path was opened rather than rejected or parsed.
    f = tmp_path / "room.toml"
    f.write_text("[ceiling]\nlength = 2.0\n")
    with pytest.raises(Exception) as e:
        kappe.ceiling(f)
    assert not isinstance(e.value, (TypeError, FileNotFoundError))


def test_refusals_name_force_true_not_the_cli_flags(tmp_path):
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("my own file")
    r = kappe.design(kappe.Design({"cap": {"length": 0.05}, "print": {"layer_height": 0.015}}), robot=False)
    with pytest.raises(ValueError) as e:
        r.write(str(foreign))
    msg = str(e.value)
    assert "force=True" in msg, msg
    assert "--force" not in msg and "--out" not in msg, msg
    assert (foreign / "notes.txt").read_text() == "my own file"
