"""The GIL is released during a solve; Ctrl-C stops it promptly; callbacks that raise stop it."""

import os
import signal
import subprocess
import sys
import threading
import time

import pytest

import cellseq
from conftest import instance_path


def test_a_second_thread_runs_during_a_solve():
    inst = cellseq.read(instance_path("tsplib-sop", "rbg109a.sop"))
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.005)

    t = threading.Thread(target=count)
    t.start()
    t0 = time.perf_counter()
    try:
        r = cellseq.solve(inst, "ils", time_limit=1.0, lower_bound=False)
    finally:
        done.set()
        t.join()
    during = [x for x in ticks if t0 < x < t0 + r.elapsed_s]
    # the ticker wakes about 200 times a second; with the GIL held it could not run at all
    # (a loaded machine may wake it far less often: 5 is enough to tell)
    assert len(during) >= 5, (len(during), r.elapsed_s)


def test_two_solves_in_two_threads_agree_with_one():
    inst = cellseq.read(instance_path("tsplib-sop", "ESC25.sop"))
    out = {}

    def run(seed):
        out[seed] = cellseq.solve(inst, "ils", max_evals=100_000, seed=seed).sequence

    ts = [threading.Thread(target=run, args=(s,)) for s in (1, 2)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    assert out[1] == cellseq.solve(inst, "ils", max_evals=100_000, seed=1).sequence
    assert out[2] == cellseq.solve(inst, "ils", max_evals=100_000, seed=2).sequence


def test_a_raising_callback_stops_the_solve():
    inst = cellseq.read(instance_path("tsplib-sop", "rbg109a.sop"))

    class Stop(Exception):
        pass

    def cb(evals, seconds, best):
        raise Stop(best)

    t0 = time.perf_counter()
    with pytest.raises(Stop):
        cellseq.solve(inst, "ils", time_limit=60, progress=cb)
    assert time.perf_counter() - t0 < 30


SCRIPT = """
import sys, cellseq
inst = cellseq.read(sys.argv[1])
print("ready", flush=True)
try:
    cellseq.solve(inst, "ils", time_limit=120, lower_bound=False)
except KeyboardInterrupt:
    print("interrupted", flush=True)
    sys.exit(3)
print("finished", flush=True)
"""


def test_ctrl_c_raises_keyboard_interrupt_promptly():
    path = instance_path("tsplib-sop", "rbg109a.sop")
    p = subprocess.Popen(
        [sys.executable, "-c", SCRIPT, path],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert p.stdout.readline().strip() == "ready"
        time.sleep(0.5)  # well inside the solve
        t0 = time.perf_counter()
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=60)
        waited = time.perf_counter() - t0
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 3, (out, err)
    assert "interrupted" in out
    # a solve of 120 s ends within a moment of the signal (the caller polls every 20 ms, the
    # solver stops at its next budget check); 30 s is a margin for a loaded machine
    assert waited < 30, waited
