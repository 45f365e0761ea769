"""A controller written in Python, in the loop at 10 Hz: satsim's ``Simulation`` against
MuJoCo's ``mj_step`` loop with ``d.ctrl``, on the same spacecraft and step (issue 26).

    python python/benches/fsw_vs_mujoco.py [--repeat N] [--duration S]

The spacecraft is benches/peers/orbit.toml's: the preprint satellite (bus, 3-DOF gimbal
through two massless links, three panels) with hinge springs and dampers and three reaction
wheels, no gravity; it goes to MuJoCo through benches/peers/mjcf.py (the peer comparison's
converter), with a motor actuator on each wheel joint. Both integrate with RK4 at 0.01 s; at
each 10 Hz tick the same rate-damping law, ``wheel torque = k * omega_bus`` per axis, is
computed in Python from the state and set as the wheels' motor torques (satsim:
``set_inputs``; MuJoCo: ``d.ctrl``), then the simulation advances 0.1 s (satsim:
``advance(0.1)``; MuJoCo: 10 calls of ``mj_step``). Before timing, the two runs' final bus
rates are compared (they are the same physics, so they must agree).

Times are the best of N; the per-tick overhead of satsim's loop is its time less
``satsim.run`` of the same scene with the law off (no Python in the loop). Needs ``mujoco``
and the ``satsim`` package; not part of CI (timing is not a test).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import satsim

ROOT = Path(__file__).resolve().parents[2]
PEERS = ROOT / "benches" / "peers"
SCENE = PEERS / "orbit.toml"
sys.path.insert(0, str(PEERS))
import mjcf  # noqa: E402

RATE, STEP, GAIN = 10.0, 0.01, 0.5


def scene_text(duration: float) -> str:
    text = SCENE.read_text()
    for old, new in (
        ("duration = 5926.0", f"duration = {duration}"),
        ("step = 0.1", f"step = {STEP}"),
        ("every = 5926.0", f"every = {duration}"),
    ):
        assert old in text, old
        text = text.replace(old, new, 1)
    return text


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
    ap.add_argument("--duration", type=float, default=600.0)
    args = ap.parse_args()
    import mujoco

    duration = args.duration
    text = scene_text(duration)
    n = int(round(duration * RATE))
    dt = 1.0 / RATE

    def satsim_loop():
        with satsim.Simulation(text, base_dir=PEERS) as sim:
            for _ in range(n):
                r = sim.row()
                sim.set_inputs({f"wheel_{a}": GAIN * r[f"omega_{a}"] for a in "xyz"})
                sim.advance(dt)
            return sim.row()

    def satsim_run():
        satsim.run(text, base_dir=PEERS)

    xml, _, wheels = mjcf.write(SCENE, timestep=STEP)
    actuators = "".join(f'<motor joint="{w}" gear="1"/>' for w in wheels)
    xml = xml.replace("</mujoco>", f"<actuator>{actuators}</actuator>\n</mujoco>")
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    per = int(round(dt / m.opt.timestep))
    assert abs(per * m.opt.timestep - dt) < 1e-12

    def mujoco_loop():
        mujoco.mj_resetData(m, d)
        mjcf.initial_state(mujoco, m, d, SCENE)
        for _ in range(n):
            d.ctrl[:] = GAIN * d.qvel[3:6]  # the bus rate, body axes
            for _ in range(per):
                mujoco.mj_step(m, d)
        return d.qvel[3:6].copy()

    # Validation: the same law on the same spacecraft gives the same bus rate.
    ours = satsim_loop()
    theirs = mujoco_loop()
    w_ours = np.array([ours[f"omega_{a}"] for a in "xyz"])
    diff = np.max(np.abs(w_ours - theirs)) / max(np.max(np.abs(theirs)), 1e-300)
    print(f"final bus rate: satsim {w_ours}, MuJoCo {theirs}, relative difference {diff:.1e}")

    t_run = best(satsim_run, args.repeat)
    t_sat = best(satsim_loop, args.repeat)
    t_mj = best(mujoco_loop, args.repeat)
    print(
        f"{SCENE.name} with RK4 dt = {STEP} s, {duration:.0f} s at {RATE:.0f} Hz "
        f"({n} ticks), best of {args.repeat}"
    )
    print(f"  satsim.run, no Python in the loop    {t_run:8.3f} s")
    print(
        f"  satsim Simulation loop               {t_sat:8.3f} s  {t_sat / n * 1e6:7.1f} us/tick, "
        f"overhead {(t_sat - t_run) / n * 1e6:6.1f} us/tick"
    )
    print(f"  MuJoCo mj_step loop with d.ctrl      {t_mj:8.3f} s  {t_mj / n * 1e6:7.1f} us/tick")
    print(f"  MuJoCo / satsim                      {t_mj / t_sat:8.2f}x")


if __name__ == "__main__":
    main()
