"""Benchmark (kept out of CI): two scenes one after the other against two Python threads at
once. The module releases the GIL while it computes, so on a machine with two free cores the
threaded wall time approaches half the sequential one.

    python python/benches/threads.py [SCENE] [--repeats N]
"""

from __future__ import annotations

import argparse
import statistics
import threading
import time
from pathlib import Path

import satsim

ROOT = Path(__file__).resolve().parents[2]


def sequential(scene: Path) -> float:
    t0 = time.perf_counter()
    satsim.run(scene)
    satsim.run(scene)
    return time.perf_counter() - t0


def threaded(scene: Path) -> float:
    threads = [threading.Thread(target=satsim.run, args=(scene,)) for _ in range(2)]
    t0 = time.perf_counter()
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default=ROOT / "examples/scenes/deploy.toml", type=Path)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    satsim.run(args.scene)  # warm-up
    seq, par = [], []
    for _ in range(args.repeats):
        seq.append(sequential(args.scene))
        par.append(threaded(args.scene))
    s, p = statistics.median(seq), statistics.median(par)
    print(f"scene {args.scene}: two runs, median of {args.repeats}")
    print(f"  sequential  {s:.3f} s")
    print(f"  2 threads   {p:.3f} s   (speed-up {s / p:.2f}x)")


if __name__ == "__main__":
    main()
