"""Speed-up of the buildability Monte Carlo on a Dask ``LocalCluster`` from 1 to 2 workers
(issue 24), printed as a table.

    python python/bench/mc_dask.py SPEC.toml [--samples 10000] [--batches 8] [--seed 1]

``SPEC.toml`` is a buildability spec with ``[uncertainty]`` (e.g. ``kappe init --kind
buildability`` with a scatter appended). Each worker is a process with one thread and one
Rayon thread (``RAYON_NUM_THREADS=1``, set before the cluster starts), so the workers are the
only parallelism. Per worker count, on a fresh cluster: the cold run (the spec's interpolation
tables built in parts over the workers, joined and shipped to every batch, then the samples),
wall seconds, and the merged P_f, which must be the same bit for bit in every row and equal to
the local run's. The load average is printed next to each row: the machine is shared.
"""

from __future__ import annotations

import argparse
import os
import time
from typing import Any, Dict, List, Tuple

os.environ["RAYON_NUM_THREADS"] = "1"

import kappe  # noqa: E402


def timed(spec: str, samples: int, seed: int, client: Any, batches: int) -> Tuple[float, Dict[str, Any]]:
    t0 = time.perf_counter()
    mc = kappe.buildability_monte_carlo(spec, samples, seed=seed, client=client, batches=batches)
    return time.perf_counter() - t0, mc


def main() -> None:
    import distributed

    ap = argparse.ArgumentParser()
    ap.add_argument("spec")
    ap.add_argument("--samples", type=int, default=10_000)
    ap.add_argument("--batches", type=int, default=8)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    with open(a.spec, encoding="utf-8") as f:
        text = f.read()
    rows: List[Tuple[int, float, float, float]] = []
    for workers in (1, 2):
        with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True) as cluster:
            with distributed.Client(cluster) as client:
                cold, mc = timed(text, a.samples, a.seed, client, a.batches)
                rows.append((workers, cold, mc["pf"], os.getloadavg()[0]))
    local = kappe.buildability_monte_carlo(text, a.samples, seed=a.seed)
    base = rows[0]
    print(f"{a.samples} samples in {a.batches} batches, one thread per worker, cold (tables built in parts, shipped)")
    print("workers | cold s (tables + sampling) | speed-up | P_f | load")
    for w, cold, pf, load in rows:
        print(f"{w:7d} | {cold:26.2f} | {base[1] / cold:8.2f} | {pf:.4f} | {load:.1f}")
    assert all(r[2] == local["pf"] for r in rows), "the merged P_f differs from the local run"


if __name__ == "__main__":
    main()
