"""The cost of Python in the loop: a 10 Hz loop over 600 s of examples/scenes/deploy.toml.

    python python/benches/step_loop.py [--repeat N]

Times, best of N:
  run      satsim.run of the same 600 s (no Python in the loop);
  advance  6000 calls of sim.advance(0.1);
  loop     6000 ticks of row() -> set_inputs() -> advance(0.1) (a controller's loop).
The overhead per call is (time of the loop - time of the run) / 6000. With `mujoco`
importable, the same 10 Hz loop over a comparable model (a free body with five hinged
links) with mj_step is timed too, for scale.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import satsim

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "examples" / "scenes"
DURATION, RATE = 600.0, 10.0


def scene_text() -> str:
    text = (SCENES / "deploy.toml").read_text()
    assert "duration = 300.0" in text
    return text.replace("duration = 300.0", f"duration = {DURATION}", 1)


def best(f, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    text = scene_text()
    n = int(round(DURATION * RATE))
    dt = 1.0 / RATE

    def run():
        satsim.run(text, base_dir=SCENES)

    def advance():
        with satsim.Simulation(text, base_dir=SCENES) as sim:
            for _ in range(n):
                sim.advance(dt)

    def loop():
        with satsim.Simulation(text, base_dir=SCENES) as sim:
            for _ in range(n):
                r = sim.row()
                sim.set_inputs({"wheel_x": 1e-3 * r["omega_x"]})
                sim.advance(dt)

    t_run = best(run, args.repeat)
    t_adv = best(advance, args.repeat)
    t_loop = best(loop, args.repeat)
    print(f"deploy.toml, {DURATION:.0f} s at {RATE:.0f} Hz ({n} calls), best of {args.repeat}")
    print(f"  satsim.run (no Python in the loop)   {t_run:8.3f} s")
    print(
        f"  advance(0.1) x {n}                   {t_adv:8.3f} s   "
        f"{t_adv / n * 1e6:8.1f} us/call, overhead {(t_adv - t_run) / n * 1e6:8.1f} us/call"
    )
    print(
        f"  row + set_inputs + advance x {n}     {t_loop:8.3f} s   "
        f"{t_loop / n * 1e6:8.1f} us/tick, overhead {(t_loop - t_run) / n * 1e6:8.1f} us/tick"
    )
    try:
        import mujoco  # type: ignore
    except ImportError:
        print("  mujoco not importable: no comparison")
        return
    xml = """
<mujoco><option timestep="0.01" integrator="RK4" gravity="0 0 0"/>
<worldbody><body name="bus"><freejoint/><geom type="box" size="1 1 1" mass="1000"/>
""" + "".join(
        f'<body pos="{1.2 + k} 0 0"><joint type="hinge" axis="0 0 1" stiffness="2" damping="4"/>'
        f'<geom type="box" size="0.5 1 0.05" mass="50"/>'
        for k in range(5)
    ) + "</body>" * 5 + "</body></worldbody></mujoco>"
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    per = int(round(dt / model.opt.timestep))

    def mj_loop():
        mujoco.mj_resetData(model, data)
        for _ in range(n):
            data.ctrl[:] = 0.0
            for _ in range(per):
                mujoco.mj_step(model, data)

    t_mj = best(mj_loop, args.repeat)
    print(f"  mujoco mj_step loop (RK4 0.01 s, 6 bodies) {t_mj:8.3f} s   {t_mj / n * 1e6:8.1f} us/tick")


if __name__ == "__main__":
    main()
