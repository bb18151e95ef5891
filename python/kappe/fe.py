"""Shell finite elements: linear buckling of a mesh given as a dict in the fixture JSON format
(what ``kappe fe buckle`` reads)."""

from __future__ import annotations

import json
from typing import Any, Dict, Mapping, Union

import numpy as np

from . import _kappe

__all__ = ["buckle"]


def buckle(mesh: Union[str, Mapping[str, Any]], modes: int = 1, sturm_check: bool = True) -> Dict[str, Any]:
    """Buckling factors (ascending, NumPy array) and mode shapes (list of n×6 arrays)."""
    if isinstance(modes, bool) or not isinstance(modes, int) or modes < 1:
        raise ValueError(f"modes: expected a whole number >= 1, got {modes!r}")
    text = mesh if isinstance(mesh, str) else json.dumps(mesh, allow_nan=False)
    r = json.loads(_kappe.fe_buckle(text, modes, bool(sturm_check)))
    return {
        "factors": np.asarray(r["factors"], dtype=float),
        "modes": [np.asarray(m, dtype=float) for m in r["modes"]],
    }
