"""Combinatorial Equilibrium Modeling: ``solve`` and ``optimize`` a topology given as a dict in
the ``kappe.cem.topology`` JSON shape (what ``kappe cem solve`` reads)."""

from __future__ import annotations

import json
from typing import Any, Dict, Mapping, Union

from . import _kappe

__all__ = ["solve", "optimize"]


def _text(topology: Union[str, Mapping[str, Any]]) -> str:
    if isinstance(topology, str):
        return topology
    if isinstance(topology, Mapping):
        return json.dumps(topology, allow_nan=False)
    raise TypeError(f"topology: expected a dict or JSON text, got {type(topology).__name__}")


def solve(topology: Union[str, Mapping[str, Any]], force_polygons: bool = False) -> Dict[str, Any]:
    """The equilibrium of a topology, as the dict ``kappe cem solve`` writes. The GIL is
    released while solving."""
    return json.loads(_kappe.cem_solve(_text(topology), bool(force_polygons)))


def optimize(topology: Union[str, Mapping[str, Any]]) -> Dict[str, Any]:
    """Constrained form-finding of a topology with an ``optimization`` block:
    ``{"converged", "status", "objective", "equilibrium"}``."""
    return json.loads(_kappe.cem_optimize(_text(topology)))
