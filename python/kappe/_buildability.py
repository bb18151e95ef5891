"""The print's Monte Carlo of a buildability spec with ``[uncertainty]`` (issue 24):
``kappe.buildability_monte_carlo(spec, samples, seed)`` samples every layer count of the print
locally, or one Dask task per batch when given a ``dask.distributed.Client``. The batches are
the library's (``kappe buildability`` runs the same functions in one batch), so the merged result
equals the local run with the same seed, bit for bit, whatever the number of batches."""

from __future__ import annotations

import json
from typing import Any, Dict, List, Optional

from . import _kappe
from ._source import PathOrText, read_source

__all__ = ["buildability_monte_carlo"]


def _batch(text: str, samples: int, seed: int, index: int, count: int) -> str:
    # A module-level function: Dask pickles it by reference to run it on the workers. Each
    # worker process builds the spec's interpolation tables once and keeps them.
    result: str = _kappe.buildability_mc_batch(text, samples, seed, index, count)
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
    ``client`` the run is cut into ``batches`` (default: two per worker) tasks."""
    text, _, _ = read_source(spec, "buildability")
    parts: List[str]
    if client is None:
        n = batches or 1
        parts = [_batch(text, samples, seed, i, n) for i in range(n)]
    else:
        n = batches or 2 * max(1, len(client.scheduler_info().get("workers", {})))
        futures = client.map(_batch, [text] * n, [samples] * n, [seed] * n, list(range(n)), [n] * n, pure=False)
        parts = client.gather(futures)
    merged: Dict[str, Any] = json.loads(_kappe.buildability_mc_merge(parts))
    return merged
