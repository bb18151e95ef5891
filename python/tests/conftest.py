import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
FIXTURES = ROOT.parent / "shared" / "fixtures"

# A cheap design (3 centre layers of 15 mm, 13 states): fast enough for every test.
CHEAP = {"cap": {"length": 0.05}, "print": {"layer_height": 0.015}}


@pytest.fixture(scope="session")
def kappe_bin():
    path = pathlib.Path(os.environ.get("KAPPE_BIN", ROOT / "target" / "release" / "kappe"))
    if not path.is_file():
        subprocess.run(["cargo", "build", "--release", "-p", "kappe-cli"], cwd=ROOT, check=True)
    return str(path)
