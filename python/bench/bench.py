"""Speed of the Python package against the CLI and the Rust bench (issue 12 targets).

    python python/bench/bench.py [--kappe-bin target/release/kappe] [--repeat 3]
                                 [--rust-us 146] [--skip-design] [--skip-cem]

* ``kappe.design()`` of the default design vs ``kappe design --allow-fail -q`` of the same
  design. Each run is a fresh process (so both pay start-up and imports); wall time and CPU
  time (user + sys of the child, from ``getrusage``) per run, runs interleaved so load from
  other work hits both alike, and the load average next to each. Two Python rows: the call
  alone (what the target is about; results are converted when read) and the call plus reading
  every part of the result (summary, states, layers, path, trajectory, network, constraints,
  report), which is the work the CLI does when it writes its files.
* ``kappe.cem.Topology(t).solve()`` on ``vault_grid500`` (the fixture of
  ``cargo bench -p cem --bench cem -- vault_grid500``): median of many calls, against the Rust
  bench's ``solve_full::vault_grid500`` median given with ``--rust-us`` (run the bench for it;
  timing it here would need its own build).
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from typing import Dict, List, Tuple

ROOT = pathlib.Path(__file__).resolve().parents[2]
FIXTURE = ROOT.parent / "shared" / "fixtures" / "cem" / "vault_grid500.input.json"

PY_CALL = "import kappe; kappe.design(allow_fail=True)"
PY_ALL = (
    "import kappe; r = kappe.design(allow_fail=True); "
    "(r.summary, r.states, r.layers, r.path, r.trajectory, r.network, r.constraints, r.report_html)"
)


def child(cmd: List[str]) -> Tuple[float, float, float]:
    """(wall s, CPU s, load average) of one child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, load


def design_rows(kappe_bin: str, repeat: int) -> None:
    runs: Dict[str, List[Tuple[float, float, float]]] = {"cli": [], "py": [], "py_all": []}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(repeat):
            out = os.path.join(tmp, f"out{i}")
            runs["cli"].append(child([kappe_bin, "design", "--out", out, "-q", "--allow-fail"]))
            runs["py"].append(child([sys.executable, "-c", PY_CALL]))
            runs["py_all"].append(child([sys.executable, "-c", PY_ALL]))
    names = {
        "cli": "kappe design (CLI)",
        "py": "kappe.design()",
        "py_all": "kappe.design() + read every part",
    }
    cli_cpu = statistics.median(r[1] for r in runs["cli"])
    cli_wall = statistics.median(r[0] for r in runs["cli"])
    print(f"default design, {repeat} runs each, interleaved (median; per run: wall/CPU s @ load)")
    print(f"{'':34} {'wall s':>8} {'CPU s':>8} {'CPU vs CLI':>10} {'wall vs CLI':>11}  runs")
    for key, rows in runs.items():
        wall = statistics.median(r[0] for r in rows)
        cpu = statistics.median(r[1] for r in rows)
        each = "  ".join(f"{w:.1f}/{c:.1f}@{ld:.1f}" for w, c, ld in rows)
        print(
            f"{names[key]:34} {wall:8.2f} {cpu:8.2f} {100 * (cpu / cli_cpu - 1):+9.1f}% "
            f"{100 * (wall / cli_wall - 1):+10.1f}%  {each}"
        )


def cem_rows(rust_us: float, n: int) -> None:
    import kappe

    topo = kappe.cem.Topology(json.loads(FIXTURE.read_text()))
    for _ in range(50):  # warm-up: caches, allocator, rayon pool
        topo.solve()
    samples = []
    for _ in range(n):
        t0 = time.perf_counter()
        topo.solve()
        samples.append(time.perf_counter() - t0)
    med = statistics.median(samples) * 1e6
    print(
        f"\nvault_grid500, kappe.cem.Topology(t).solve(): median {med:.1f} µs of {n} calls "
        f"(min {min(samples) * 1e6:.1f} µs), load {os.getloadavg()[0]:.1f}"
    )
    if rust_us > 0:
        print(
            f"  Rust bench solve_full::vault_grid500 median {rust_us:.1f} µs -> {med / rust_us:.2f}x "
            f"(overhead {med - rust_us:.1f} µs; target <= 2x)"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kappe-bin", default=str(ROOT / "target" / "release" / "kappe"))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rust-us", type=float, default=0.0, help="the Rust bench median, µs")
    ap.add_argument("--cem-calls", type=int, default=2000)
    ap.add_argument("--skip-design", action="store_true")
    ap.add_argument("--skip-cem", action="store_true")
    a = ap.parse_args()
    if not a.skip_design:
        design_rows(a.kappe_bin, a.repeat)
    if not a.skip_cem:
        cem_rows(a.rust_us, a.cem_calls)


if __name__ == "__main__":
    main()
