"""Ctrl-C stops a running ``kappe.design()``: a real SIGINT sent to a Python process that runs
the default design (not the progress-callback route of test_design.py)."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

# The child writes the marker on the first progress callback of the given stage (the run has
# started, the GIL is released and the native code is computing), then reports how the run
# ended on stdout.
CHILD = textwrap.dedent(
    """
    import signal, sys, time
    import kappe

    # Python keeps SIGINT ignored when it starts ignored (a job started with `&` by a
    # non-interactive shell, e.g. a CI script run in the background): install the default
    # KeyboardInterrupt handler, which is what this test is about.
    signal.signal(signal.SIGINT, signal.default_int_handler)

    marker, when = sys.argv[1], sys.argv[2]
    started = []

    def progress(stage, done, total):
        if not started and stage == when:
            started.append(stage)
            with open(marker, "w") as f:
                f.write(stage)

    try:
        kappe.design(kappe.Design(), allow_fail=True, progress=progress)
    except KeyboardInterrupt:
        print("KeyboardInterrupt", time.monotonic(), flush=True)
        sys.exit(3)
    print("finished", flush=True)
    """
)

# Start-up (import, first state) on a loaded 2-core machine: generous, it only bounds a hang.
START_TIMEOUT_S = 180.0
# From SIGINT to the process's end. The caller's thread checks for signals every 50 ms; the
# worker then stops at its next check, before the next print state in form-finding or the next
# state's buckling analysis, so at most the FE analyses already running finish (one state of
# the default cap is ~0.2-1 s of CPU; rayon runs one per core). 20 s allows for 10x slowdown on
# a loaded 2-core machine and is still far below the ~20-40 s the rest of the run would take,
# so a run that ignores Ctrl-C cannot pass: it would also print "finished", not the exception.
STOP_TOLERANCE_S = 20.0


@pytest.mark.parametrize("stage", ["states", "analysis"])
def test_sigint_stops_the_default_design(tmp_path, stage):
    """SIGINT during form-finding, and during the finite-element analysis (states analysed in
    parallel, the longest stage)."""
    marker = tmp_path / "started"
    proc = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(marker), stage],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while not marker.exists():
            assert proc.poll() is None, f"the child ended before it started: {proc.communicate()}"
            assert time.monotonic() < deadline, "the run did not start (no progress callback)"
            time.sleep(0.05)
        sent = time.monotonic()
        os.kill(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=STOP_TOLERANCE_S + 30.0)
        ended = time.monotonic()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert out.startswith("KeyboardInterrupt"), (out, err)
    assert proc.returncode == 3, (proc.returncode, err)
    # The child's own clock stamp: when the exception reached Python code (same monotonic
    # clock as ours on Linux); the process end follows it by the interpreter's shutdown.
    caught = float(out.split()[1])
    print(f"{stage}: SIGINT -> KeyboardInterrupt in {caught - sent:.2f} s, process ended after {ended - sent:.2f} s")
    assert caught - sent < STOP_TOLERANCE_S
    assert ended - sent < STOP_TOLERANCE_S + 10.0
