"""Speed-up of the buildability Monte Carlo on a Dask ``LocalCluster`` from 1 to 2 workers
(issue 24), printed as a table.

    python python/bench/mc_dask.py SPEC.toml [--samples 10000] [--batches 8] [--seed 1]

``SPEC.toml`` is a buildability spec with ``[uncertainty]`` (e.g. ``kappe init --kind
buildability`` with a scatter appended). Each worker is a process with one thread and one
Rayon thread (``RAYON_NUM_THREADS=1``, set before the cluster starts), so the workers are the
only parallelism. Per worker count: the cold run (every worker builds the spec's interpolation
tables on its first batch, then samples) and the warm run (tables already built on every worker:
the sampling alone), wall seconds, and the merged P_f, which must be the same bit for bit in
every row. The load average is printed next to each row: the machine is shared.
"""

from __future__ import annotations

import argparse
import os
import time
from typing import Any, Dict, List, Tuple

os.environ["RAYON_NUM_THREADS"] = "1"

import kappe  # noqa: E402
from kappe._buildability import _batch  # noqa: E402


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
    rows: List[Tuple[int, float, float, float, float]] = []
    for workers in (1, 2):
        with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True) as cluster:
            with distributed.Client(cluster) as client:
                cold, mc = timed(text, a.samples, a.seed, client, a.batches)
                # Every worker has built the tables now (or builds them here, untimed).
                client.run(_batch, text, 100, 0, 0, 1)
                warm, mc2 = timed(text, a.samples, a.seed, client, a.batches)
                assert mc == mc2
                rows.append((workers, cold, warm, mc["pf"], os.getloadavg()[0]))
    base = rows[0]
    print(f"{a.samples} samples in {a.batches} batches, one thread per worker")
    print("workers | cold s (tables + sampling) | warm s (sampling) | speed-up cold | warm | P_f | load")
    for w, cold, warm, pf, load in rows:
        print(
            f"{w:7d} | {cold:26.2f} | {warm:17.2f} | {base[1] / cold:13.2f} | {base[2] / warm:4.2f} | "
            f"{pf:.4f} | {load:.1f}"
        )
    assert all(r[3] == base[3] for r in rows), "the merged P_f differs between worker counts"


if __name__ == "__main__":
    main()
