import importlib.util
import pathlib

from conftest import CHEAP


def test_rhino_example_runs_outside_rhino():
    path = pathlib.Path(__file__).resolve().parents[1] / "examples" / "rhino_cap.py"
    assert path.read_text().startswith("# r: kappe")
    spec = importlib.util.spec_from_file_location("rhino_cap", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    result, layers, path_pts = mod.main(CHEAP)
    assert len(layers) == len(result.layers)
    assert all(len(p) == 3 for p in path_pts)
    assert len(path_pts) == len(result.path.points)
