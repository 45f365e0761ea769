"""MuJoCo's stepping loop alone, for an instruction count (issue 11): 600 s of the orbit
scene (6000 RK4 steps at 0.1 s) in one `mj_step(m, d, nstep)` call. Wall time is noise on
a shared machine; instructions are not:

    valgrind --tool=callgrind --toggle-collect=mj_step \\
        /tmp/peers-venv/bin/python benches/peers/mj_steps.py

counts only what runs inside `mj_step` (each RK4 step evaluates the dynamics four times).
Compare with `valgrind --tool=callgrind target/release/satsim run <orbit.toml with
duration = 600>` (docs/src/engineering/floor.md, "The earlier analyses").
"""

import os
import sys
from pathlib import Path

import mujoco

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import mjcf  # noqa: E402

SCENE = HERE / "orbit.toml"
STEPS = int(os.environ.get("STEPS", "6000"))

scene = mjcf.load(SCENE)[0]
xml, _, _ = mjcf.write(SCENE, timestep=scene["integrator"]["step"])
m = mujoco.MjModel.from_xml_string(xml)
d = mujoco.MjData(m)
mujoco.set_mjcb_time(None)  # no profiling timers
mjcf.initial_state(mujoco, m, d, SCENE)
mujoco.mj_step(m, d, nstep=STEPS)
print(f"{STEPS} steps, t = {d.time:.1f} s, qpos[3:7] = {d.qpos[3:7]}")
