"""Combinatorial Equilibrium Modeling: ``solve`` and ``optimize`` a topology given as a dict in
the ``kappe.cem.topology`` JSON shape (what ``kappe cem solve`` reads)."""

from __future__ import annotations

import json
from typing import Any, Dict, Mapping, Union

from . import _kappe

__all__ = ["solve", "optimize", "Topology"]


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
    ``{"converged", "status", "objective", "equilibrium", "report"}``; ``equilibrium`` is the
    document ``kappe cem optimize`` writes (with its ``optimization`` block), ``report`` the
    text it prints."""
    return json.loads(_kappe.cem_optimize(_text(topology)))


class Topology:
    """A topology parsed once, to solve many times (no JSON round trip per solve):
    ``Topology(dict).solve()`` returns NumPy arrays ``xyz`` (n×3), ``trail_forces``,
    ``deviation_forces`` and ``reactions`` (n×3)."""

    def __init__(self, topology: Union[str, Mapping[str, Any]]) -> None:
        self._native = _kappe.Topology(_text(topology))

    def solve(self) -> Dict[str, Any]:
        """The arrays, made in Rust from the solver's vectors (no lists, no copy)."""
        return self._native.solve()
