"""What stepping in pieces costs under an adaptive method: the flexible deployment
(examples/flexible_array.toml, Radau IIA) over 60 s, as one run and in advance(dt) pieces.

    python python/benches/step_pieces.py [--repeat N]

Times, best of N: satsim.run of the 60 s, then 60/dt calls of sim.advance(dt) for dt = 1,
0.1 and 0.02 s. Each piece goes on from the last with its proposed step and Radau IIA's
Jacobian, so a short piece costs a step or two (docs: "Python", the stepping API).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import satsim
from step_loop import best  # the same best-of-N timer

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "examples" / "flexible_array.toml"
DURATION = 60.0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    text = SCENE.read_text()
    assert "duration = 300.0" in text
    text = text.replace("duration = 300.0", f"duration = {DURATION}", 1)

    def run():
        satsim.run(text, base_dir=SCENE.parent)

    def pieces(dt: float):
        def f():
            with satsim.Simulation(text, base_dir=SCENE.parent) as sim:
                for _ in range(int(round(DURATION / dt))):
                    sim.advance(dt)

        return f

    print(f"flexible_array.toml, {DURATION:.0f} s, best of {args.repeat}")
    print(f"  satsim.run              {1e3 * best(run, args.repeat):8.1f} ms")
    for dt in (1.0, 0.1, 0.02):
        n = int(round(DURATION / dt))
        t = best(pieces(dt), args.repeat)
        print(f"  advance({dt:g}) x {n:<5d}    {1e3 * t:8.1f} ms")


if __name__ == "__main__":
    main()
