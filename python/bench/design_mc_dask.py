"""Speed-up of a design's Monte Carlo on a Dask ``LocalCluster`` from 1 to 2 workers (issue 24:
"10⁴ samples of the default cap's governing states on a Dask LocalCluster with a measured
speed-up from 1 to 2 workers"), printed as a table.

    python python/bench/design_mc_dask.py [--samples 10000] [--batches 8] [--seed 1] [--design FILE]

The design defaults to the default cap with form_cost's time parameters (E(t) = 10 MPa +
1 kPa/s·t; E₀ lognormal cov 0.2, Ė lognormal cov 0.3, γ normal cov 0.05, E₀ drifting −20 %/h;
FORM P_f ≈ 2e-9, so the samples are importance samples around the design points). Each worker
is a process with one thread and one Rayon thread (``RAYON_NUM_THREADS=1``), so the workers are
the only parallelism. The plan (the design's run with FORM: one task whatever the workers) runs
once, timed apart; then per worker count, on a fresh cluster (cold), the Monte Carlo proper —
the tables in parts over the workers, the setup, the batches; the merged P_f must be the same
bits in both rows. The load average is printed: the machine is shared.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from typing import Any, List, Tuple

from kappe import _design_mc as mc
from kappe import _kappe

DEFAULT_CAP = """name = "default"
[material.time]
model = "linear"
youngs_modulus = 1.0e7
youngs_modulus_rate = 1000.0
[uncertainty]
"material.time.youngs_modulus" = { dist = "lognormal", cov = 0.2 }
"material.time.youngs_modulus_rate" = { dist = "lognormal", cov = 0.3 }
"material.specific_weight" = { dist = "normal", cov = 0.05 }
[uncertainty.drift]
"material.time.youngs_modulus" = { percent_per_hour = -20.0 }
"""


def run(client: Any, text: str, plan: str, batches: int) -> Tuple[float, dict]:
    # The Monte Carlo proper on a fresh cluster: the tables in parts (two per worker), the setup
    # (tables joined, importance-sampling centres), one task per batch.
    workers = max(1, len(client.scheduler_info().get("workers", {})))
    k = 2 * workers
    t0 = time.perf_counter()
    parts = client.map(mc._table_part, [text] * k, [plan] * k, list(range(k)), [k] * k, pure=False)
    setup = client.submit(mc._setup, text, plan, parts, pure=False)
    futures = client.map(
        mc._batch, [text] * batches, [setup] * batches, list(range(batches)), [batches] * batches, pure=False
    )
    got: List[str] = client.gather(futures)
    elapsed = time.perf_counter() - t0
    merged = json.loads(_kappe.design_mc_merge(setup.result(), got))
    return elapsed, merged


def main() -> None:
    import distributed

    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=10_000)
    ap.add_argument("--batches", type=int, default=8)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--design")
    a = ap.parse_args()
    text = DEFAULT_CAP
    if a.design:
        with open(a.design, encoding="utf-8") as f:
            text = f.read()
    # The plan (the design's run with FORM of every state) is one task whatever the workers:
    # run once here, on this process's Rayon threads, and timed apart. The workers, started
    # after, inherit RAYON_NUM_THREADS=1.
    t0 = time.perf_counter()
    plan = mc._plan(text, a.samples, a.seed, "auto")
    plan_s = time.perf_counter() - t0
    os.environ["RAYON_NUM_THREADS"] = "1"
    print(f"plan (the design's run with FORM, this process, all Rayon threads): {plan_s:.1f} s", flush=True)
    rows = []
    for workers in (1, 2):
        with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True) as cluster:
            with distributed.Client(cluster) as client:
                mc_s, m = run(client, text, plan, a.batches)
                rows.append((workers, mc_s, m, os.getloadavg()[0]))
                print(f"{workers} worker(s): {mc_s:.1f} s, P_f {m['pf']!r}", flush=True)
    base = rows[0]
    print(f"{a.samples} samples in {a.batches} batches, one thread per worker, cold (tables in parts, shipped)")
    print(
        "workers | Monte Carlo s (tables + setup + batches) | speed-up | method | P_f | 95 % interval | "
        "FORM P_f | states | table solves | load"
    )
    for w, m_s, m, load in rows:
        print(
            f"{w:7d} | {m_s:40.1f} | {base[1] / m_s:8.2f} | {m['method']} | {m['pf']:.4e} | "
            f"[{m['pf_interval'][0]:.4e}, {m['pf_interval'][1]:.4e}] | {m['form_pf']:.4e} | "
            f"{len(m['states'])} | {m['table_solves']} | {load:.1f}"
        )
    assert rows[0][2]["pf"] == rows[1][2]["pf"], "the merged P_f differs between the runs"


if __name__ == "__main__":
    main()
