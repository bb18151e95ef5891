"""The Monte Carlo of a design's governing states (issue 24): ``kappe.design_monte_carlo(design,
samples, seed)`` runs the design with its FORM reliability, picks the states that hold all but
1 % of the print's FORM P_f, tabulates their buckling factors and samples them — locally, or as
Dask tasks when given a ``dask.distributed.Client``: the plan (the design's run and FORM) as one
task, the tables in parts over the workers (two per worker), one task that joins them and finds
the importance-sampling centres, and one task per batch of samples, each shipped the joined
tables. The steps are the library's (``kappe design`` runs them in one batch), so the merged
result equals ``summary.json``'s ``reliability.monte_carlo`` with the same seed bit for bit."""

from __future__ import annotations

import json
from typing import Any, Dict, List, Optional

from . import _kappe
from ._source import PathOrText, read_source

__all__ = ["design_monte_carlo"]


def _plan(text: str, samples: int, seed: int, method: str) -> str:
    # One Dask task: the design's run with FORM, and the governing states, as JSON.
    result: str = _kappe.design_mc_plan(text, samples, seed, method)
    return result


def _table_part(text: str, plan: str, index: int, count: int) -> str:
    # One Dask task: the tables of part ``index`` of ``count`` of the governing states.
    result: str = _kappe.design_mc_table_part(text, plan, index, count)
    return result


def _setup(text: str, plan: str, parts: List[str]) -> str:
    # One Dask task: the tables joined and the importance-sampling centres (what every batch gets).
    result: str = _kappe.design_mc_setup(text, plan, parts)
    return result


def _batch(text: str, setup: str, index: int, count: int) -> str:
    # One Dask task: batch ``index`` of ``count`` of the samples. Module-level, so Dask pickles it
    # by reference.
    result: str = _kappe.design_mc_batch(text, setup, index, count)
    return result


def design_monte_carlo(
    design: PathOrText,
    samples: int,
    seed: int = 0,
    client: Optional[Any] = None,
    batches: Optional[int] = None,
    method: str = "auto",
) -> Dict[str, Any]:
    """Monte Carlo of the print of ``design`` (a path to a design file or its TOML text, with an
    ``[uncertainty]`` table; its own ``monte_carlo`` keys are ignored): ``samples`` samples drawn
    with ``seed``, ``method`` ``"auto"`` (crude when ``samples``·P_f,FORM ≥ 100, else importance),
    ``"crude"`` or ``"importance"``. Returns ``reliability.monte_carlo`` of summary.json (``pf``,
    ``pf_interval``, ``form_pf``, ``form_in_interval``, ``states`` …; ``seconds`` counts the
    tables and the batches' own seconds). Locally every step runs in this process on the Rust
    threads (the GIL released); with ``client`` the run is cut into ``batches`` (default: two per
    worker) tasks after the plan and table tasks."""
    text, _, _ = read_source(design, "design")
    parts: List[str]
    if client is None:
        plan = _plan(text, samples, seed, method)
        setup = _setup(text, plan, [_table_part(text, plan, 0, 1)])
        n = batches or 1
        parts = [_batch(text, setup, i, n) for i in range(n)]
    else:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        n = batches or 2 * workers
        k = 2 * workers
        plan_f = client.submit(_plan, text, samples, seed, method, pure=False)
        table_parts = client.map(_table_part, [text] * k, [plan_f] * k, list(range(k)), [k] * k, pure=False)
        setup_f = client.submit(_setup, text, plan_f, table_parts, pure=False)
        futures = client.map(_batch, [text] * n, [setup_f] * n, list(range(n)), [n] * n, pure=False)
        parts = client.gather(futures)
        setup = client.gather(setup_f)
    merged: Dict[str, Any] = json.loads(_kappe.design_mc_merge(setup, parts))
    return merged
