"""The GIL is released while satsim computes, so Python threads run at the same time.

No timing thresholds (timing belongs in benchmarks: `python/benches/threads.py` measures the
speed-up): the tests check that other Python code ran *during* a computation. While one thread
holds the GIL no other Python thread can run, so anything another thread records strictly
inside the middle half of a call's interval proves the call had released the GIL. (The
margins cover the few milliseconds around the call's entry and exit when a thread holding the
GIL could still be switched out.)
"""

from __future__ import annotations

import threading
import time

import numpy as np

import satsim
from conftest import SCENES

LONG = SCENES / "deploy.toml"  # about 1.5 s in a release build
SHORT = SCENES / "tumbling.toml"  # about 30 ms


def middle_half(t0, t1):
    q = 0.25 * (t1 - t0)
    return t0 + q, t1 - q


def test_python_runs_while_a_scene_runs():
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.002)

    th = threading.Thread(target=ticker)
    th.start()
    try:
        t0 = time.perf_counter()
        r = satsim.run(LONG)
        t1 = time.perf_counter()
    finally:
        stop.set()
        th.join()
    assert len(r) == 301
    lo, hi = middle_half(t0, t1)
    inside = [t for t in ticks if lo < t < hi]
    assert len(inside) >= 5, f"{len(inside)} ticks in the middle of a {t1 - t0:.3f} s run"


def test_two_threads_run_scenes_at_once():
    long_ref, short_ref = satsim.run(LONG), satsim.run(SHORT)
    a = {}
    short_done = []
    short_results = []
    failures = []
    a_finished = threading.Event()
    started = threading.Barrier(2)

    def run_long():
        try:
            started.wait()
            a["t0"] = time.perf_counter()
            a["result"] = satsim.run(LONG)
            a["t1"] = time.perf_counter()
        except BaseException as e:  # reported by the main thread
            failures.append(e)
        finally:
            a_finished.set()

    def run_short_repeatedly():
        try:
            started.wait()
            while not a_finished.is_set():
                short_results.append(satsim.run(SHORT))
                short_done.append(time.perf_counter())
        except BaseException as e:
            failures.append(e)

    threads = [threading.Thread(target=run_long), threading.Thread(target=run_short_repeatedly)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert not failures, failures
    # Both threads computed correct results (the same bits as one at a time).
    np.testing.assert_array_equal(a["result"].data, long_ref.data)
    for r in short_results:
        np.testing.assert_array_equal(r.data, short_ref.data)
    # Short scenes finished while the long one was running.
    lo, hi = middle_half(a["t0"], a["t1"])
    inside = [t for t in short_done if lo < t < hi]
    assert len(inside) >= 2, (
        f"{len(inside)} short runs finished in the middle of a {a['t1'] - a['t0']:.3f} s run"
    )
