"""The print's Monte Carlo of a buildability spec with ``[uncertainty]`` (issue 24):
``kappe.buildability_monte_carlo(spec, samples, seed)`` samples every layer count of the print
locally, or one Dask task per batch when given a ``dask.distributed.Client``. The batches are
the library's (``kappe buildability`` runs the same functions in one batch), so the merged result
equals the local run with the same seed, bit for bit, whatever the number of batches. On Dask the
spec's interpolation tables (the costly part) are built once, in parts over the workers (two per
worker, consecutive layer counts of about equal work), with the collapse tables of a spec with
``[analysis.nonlinear]`` as one more task, joined, and shipped to every batch: no worker builds
them again, and the shipped tables carry every number's bits."""

from __future__ import annotations

import json
from typing import Any, Dict, List, Optional

from . import _kappe
from ._source import PathOrText, read_source

__all__ = ["buildability_monte_carlo"]


def _table_part(text: str, index: int, count: int) -> str:
    # One Dask task: part ``index`` of ``count`` of the spec's interpolation tables, as JSON.
    result: str = _kappe.buildability_mc_table_part(text, index, count)
    return result


def _collapse(text: str) -> str:
    # One Dask task beside the parts: the collapse tables of a spec with [analysis.nonlinear]
    # (the deterministic states, then the paths of the layer counts the state rule keeps), as
    # JSON; ``null`` without it.
    result: str = _kappe.buildability_mc_collapse_tables(text)
    return result


def _join(parts: List[str], collapse: str) -> str:
    # One Dask task: the print's tables from all parts and the collapse tables, as JSON (what
    # every batch is shipped).
    result: str = _kappe.buildability_mc_tables_join(parts, collapse)
    return result


def _batch(text: str, samples: int, seed: int, index: int, count: int, tables: Optional[str] = None) -> str:
    # A module-level function: Dask pickles it by reference to run it on the workers. A worker
    # process keeps the spec's tables after its first batch: shipped ``tables`` when given, else
    # built there.
    result: str = _kappe.buildability_mc_batch(text, samples, seed, index, count, tables)
    return result


def buildability_monte_carlo(
    spec: PathOrText,
    samples: int,
    seed: int = 0,
    client: Optional[Any] = None,
    batches: Optional[int] = None,
) -> Dict[str, Any]:
    """Crude Monte Carlo of the print of ``spec`` (a path to a buildability spec or its TOML
    text, with an ``[uncertainty]`` table): ``samples`` samples drawn with ``seed``. Returns
    the ``monte_carlo`` block of buildability.json (``pf``, ``pf_interval``, ``failed_by``,
    ``state_pf``, failure-layer mean and std; ``seconds`` and ``resolves`` are 0, they belong
    to the workers). Locally one batch runs on the Rust threads (the GIL released); with
    ``client`` the run is cut into ``batches`` (default: two per worker) tasks, after the tasks
    that build the tables for them all (two parts per worker and, with ``[analysis.nonlinear]``,
    the collapse tables; then one task that joins them)."""
    text, _, _ = read_source(spec, "buildability")
    parts: List[str]
    if client is None:
        n = batches or 1
        parts = [_batch(text, samples, seed, i, n) for i in range(n)]
    else:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        n = batches or 2 * workers
        k = 2 * workers
        table_parts = client.map(_table_part, [text] * k, list(range(k)), [k] * k, pure=False)
        collapse = client.submit(_collapse, text, pure=False)
        tables = client.submit(_join, table_parts, collapse, pure=False)
        futures = client.map(
            _batch, [text] * n, [samples] * n, [seed] * n, list(range(n)), [n] * n, [tables] * n, pure=False
        )
        parts = client.gather(futures)
    merged: Dict[str, Any] = json.loads(_kappe.buildability_mc_merge(parts))
    return merged
