"""Shell finite elements: linear buckling and linear statics of a mesh given as a dict in the
fixture JSON format (what ``kappe fe buckle`` / ``kappe fe static`` read)."""

from __future__ import annotations

import json
from typing import Any, Dict, Mapping, Union

from . import _kappe

__all__ = ["buckle", "static"]


def buckle(mesh: Union[str, Mapping[str, Any]], modes: int = 1, sturm_check: bool = True) -> Dict[str, Any]:
    """The document of ``kappe fe buckle --mode-shapes`` (same element default, same keys:
    ``static``, ``dofs``, ``residuals``, ``mesh_quality``, ``sturm``, ``solver``), with the
    buckling factors (ascending) as a NumPy array and the mode shapes as a list of n×6 arrays."""
    if isinstance(modes, bool) or not isinstance(modes, int) or modes < 1:
        raise ValueError(f"modes: expected a whole number >= 1, got {modes!r}")
    text = mesh if isinstance(mesh, str) else json.dumps(mesh, allow_nan=False)
    doc, factors, shapes = _kappe.fe_buckle(text, modes, bool(sturm_check))
    r: Dict[str, Any] = json.loads(doc)
    r["factors"] = factors  # NumPy arrays made in Rust, not parsed from JSON
    r["modes"] = shapes
    return r


def static(mesh: Union[str, Mapping[str, Any]]) -> Dict[str, Any]:
    """The document of ``kappe fe static`` (same element default, same keys: ``static``,
    ``dofs``, ``element``, ``mesh_quality``, ``reactions``, ``elements``), with the nodal
    ``displacements`` (n×6: ux, uy, uz, rx, ry, rz; m, rad) as a NumPy array."""
    text = mesh if isinstance(mesh, str) else json.dumps(mesh, allow_nan=False)
    doc, displacements = _kappe.fe_static(text)
    r: Dict[str, Any] = json.loads(doc)
    r["displacements"] = displacements
    return r
