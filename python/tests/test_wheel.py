"""The wheel is one abi3 wheel for CPython >= 3.9 (Rhino 8's CPython 3.9 and any later Python):
its file name and its own WHEEL metadata carry the ``cp39-abi3`` tag, and the native module
inside is the stable-ABI one (``_kappe.abi3.so``), not a version-specific build."""

import os
import pathlib
import zipfile

import pytest


def _wheel() -> pathlib.Path:
    path = os.environ.get("KAPPE_WHEEL")
    if not path:
        pytest.skip("KAPPE_WHEEL is not set (scripts/test-python.sh sets it to the built wheel)")
    return pathlib.Path(path)


def test_wheel_is_abi3_for_cp39() -> None:
    wheel = _wheel()
    # name-version-python-abi-platform.whl
    _, _, python_tag, abi_tag, _ = wheel.stem.split("-", 4)
    assert (python_tag, abi_tag) == ("cp39", "abi3"), wheel.name
    with zipfile.ZipFile(wheel) as z:
        meta = next(n for n in z.namelist() if n.endswith(".dist-info/WHEEL"))
        tags = [line.split(":", 1)[1].strip() for line in z.read(meta).decode().splitlines() if line.startswith("Tag:")]
        assert tags and all(t.startswith("cp39-abi3-") for t in tags), tags
        natives = [n for n in z.namelist() if n.endswith(".so") or n.endswith(".pyd")]
        assert natives and all(".abi3." in n or n.endswith(".pyd") for n in natives), natives
