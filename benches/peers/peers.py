"""One orbit of the peer-comparison spacecraft (orbit.toml) with satsim, MuJoCo and Basilisk,
side by side in alternating rounds (issue 11). Not run by cargo or CI: see run.sh.

1. Validation, before anything is timed: the scene goes to MuJoCo through mjcf.py; satsim
   and MuJoCo both integrate it with RK4 at a fine step (VAL_DT, default 0.005 s, so that
   both are converged) over 600 s, and every state component (attitude, body rates, hinge
   angles and rates, wheel speeds) must agree to 1e-8 at every 10 s sample. The agreement at
   the timed step (0.1 s) is printed too (it differs by RK4's own error on the quaternion,
   which MuJoCo integrates on the manifold and satsim as four numbers renormalised).
2. Timing, ROUNDS rounds, each in turn: satsim (the whole `satsim run` process, and the
   integration alone as it reports it), MuJoCo (`mj_step(m, d, nstep=59260)`: the C loop of
   the Python package, one call, no Python per step; the timer callback `mjcb_time` set to
   None so no profiling timers run), Basilisk (`ExecuteSimulation` only, if `bsk` imports
   and its attitude and rates after 600 s agree with satsim's to 1e-8 at dt; see
   bsk_scene.py), and, with SATSIM_BEFORE=path, a second satsim binary. Medians over
   rounds and the ratios.
"""

import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import mjcf  # noqa: E402

SCENE = HERE / "orbit.toml"
ROOT = HERE.parent.parent
SATSIM = Path(os.environ.get("SATSIM", ROOT / "target" / "release" / "satsim"))
# Optional: another satsim binary (e.g. built from main) timed in the same rounds.
BEFORE = os.environ.get("SATSIM_BEFORE")
ROUNDS = int(os.environ.get("ROUNDS", "5"))
VAL_DT = float(os.environ.get("VAL_DT", "0.005"))
VAL_T = 600.0
TOL = 1e-8


def scene_variant(tmp, duration, step, every):
    """orbit.toml with another duration, step and output interval, in `tmp`."""
    text = SCENE.read_text()
    model = (HERE / mjcf.load(SCENE)[0]["model"]).resolve()
    text = re.sub(r'^model = ".*"$', f'model = "{model}"', text, flags=re.M)
    text = re.sub(r"^duration = .*$", f"duration = {duration!r}", text, flags=re.M)
    text = re.sub(r"^step = .*$", f"step = {step!r}", text, flags=re.M)
    text = re.sub(r"^every = .*$", f"every = {every!r}", text, flags=re.M)
    p = Path(tmp) / f"scene_{duration}_{step}.toml"
    p.write_text(text)
    return p


def satsim_run(scene, out, exe=None):
    """(whole-process seconds, integration seconds as reported, trajectory rows)."""
    t0 = time.perf_counter()
    r = subprocess.run([str(exe or SATSIM), "run", str(scene), "--out", str(out)], capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        sys.exit(f"satsim run failed: {r.stderr}")
    m = re.search(r"([0-9.]+) s wall", r.stdout + r.stderr)
    inner = float(m.group(1)) if m else float("nan")
    lines = (Path(out) / "trajectory.csv").read_text().splitlines()
    cols = lines[0].split(",")
    rows = [dict(zip(cols, map(float, l.split(",")))) for l in lines[1:]]
    return wall, inner, rows


def mujoco_model(dt):
    xml, hinges, wheels = mjcf.write(SCENE, timestep=dt)
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    return m, d, hinges, wheels


def mujoco_state(m, d, hinges, wheels):
    s = {}
    for k, n in enumerate(["q_w", "q_x", "q_y", "q_z"]):
        s[n] = d.qpos[3 + k]
    for k, n in enumerate(["omega_x", "omega_y", "omega_z"]):
        s[n] = d.qvel[3 + k]
    for h in hinges:
        j = m.joint(h)
        s[f"angle_{h}"] = d.qpos[j.qposadr[0]]
        s[f"rate_{h}"] = d.qvel[j.dofadr[0]]
    for w in wheels:
        s[f"{w}_speed"] = d.qvel[m.joint(w).dofadr[0]]
    return s


def compare(dt, tmp, every=10.0):
    """Largest difference between satsim and MuJoCo over VAL_T at step dt (both RK4)."""
    _, _, rows = satsim_run(scene_variant(tmp, VAL_T, dt, every), Path(tmp) / f"val_{dt}")
    m, d, hinges, wheels = mujoco_model(dt)
    mjcf.initial_state(mujoco, m, d, SCENE)
    per = round(every / dt)
    worst, where = 0.0, None
    for k, row in enumerate(rows):
        if k > 0:
            mujoco.mj_step(m, d, nstep=per)
        s = mujoco_state(m, d, hinges, wheels)
        sign = 1.0 if s["q_w"] * row["q_w"] + s["q_x"] * row["q_x"] >= 0 else -1.0
        for key, val in s.items():
            ref = row[key]
            diff = abs((sign * val if key.startswith("q_") else val) - ref)
            if diff > worst:
                worst, where = diff, (row["t"], key)
    return worst, where, len(rows)


def time_mujoco(steps, dt):
    m, d, _, _ = mujoco_model(dt)
    mujoco.set_mjcb_time(None)  # no profiling timers
    mjcf.initial_state(mujoco, m, d, SCENE)
    t0 = time.perf_counter()
    mujoco.mj_step(m, d, nstep=steps)
    return time.perf_counter() - t0


def main():
    if not SATSIM.exists():
        sys.exit(f"{SATSIM} not found: cargo build --release -p satsim-cli")
    scene = mjcf.load(SCENE)[0]
    dt, duration = scene["integrator"]["step"], scene["duration"]
    steps = round(duration / dt)
    print(f"MuJoCo {mujoco.__version__}; scene {SCENE.name}: {duration} s, RK4 dt = {dt} s, {steps} steps")
    try:
        import bsk_scene

        bsk = bsk_scene.available()
    except ImportError as e:
        bsk = None
        print(f"Basilisk: not available ({e})")
    with tempfile.TemporaryDirectory() as tmp:
        worst, where, n = compare(VAL_DT, tmp)
        print(f"validation: RK4 dt = {VAL_DT} s over {VAL_T} s, {n} samples: max |satsim - MuJoCo| = {worst:.2e} (at {where})")
        if not worst <= TOL:
            sys.exit(f"validation failed: {worst:.2e} > {TOL:.0e}; nothing timed")
        w01, where01, _ = compare(dt, tmp)
        print(f"           at the timed step dt = {dt} s: max difference {w01:.2e} (at {where01})")
        if bsk is not None:
            msg, worst_bsk = bsk_scene.validate(SCENE, satsim_run, scene_variant, tmp)
            print(msg)
            if not worst_bsk <= TOL:
                print(f"Basilisk: not timed ({worst_bsk:.2e} > {TOL:.0e})")
                bsk = None
        orbit = scene_variant(tmp, duration, dt, duration)
        res = {"satsim (process)": [], "satsim (integration)": [], "MuJoCo": []}
        if bsk is not None:
            res["Basilisk"] = []
        if BEFORE:
            res["satsim before (process)"] = []
        for r in range(ROUNDS):
            if BEFORE:
                res["satsim before (process)"].append(satsim_run(orbit, Path(tmp) / "before", BEFORE)[0])
            wall, inner, _ = satsim_run(orbit, Path(tmp) / "orbit")
            res["satsim (process)"].append(wall)
            res["satsim (integration)"].append(inner)
            res["MuJoCo"].append(time_mujoco(steps, dt))
            if bsk is not None:
                res["Basilisk"].append(bsk_scene.time_orbit(SCENE, duration, dt))
            print(f"round {r + 1}: " + ", ".join(f"{k} {v[-1]:.4f} s" for k, v in res.items()), flush=True)
    med = {k: statistics.median(v) for k, v in res.items()}
    print(f"\nmedians of {ROUNDS} alternating rounds (one orbit):")
    base = med["satsim (process)"]
    for k, v in med.items():
        print(f"  {k:22s} {v:8.4f} s   {v / base:6.2f} x satsim (process)")
    rhs = 4 * steps
    print(f"  satsim per right-hand side (integration / {rhs}): {1e6 * med['satsim (integration)'] / rhs:.3f} us")
    print(f"  MuJoCo per RK4 step: {1e6 * med['MuJoCo'] / steps:.2f} us")


if __name__ == "__main__":
    main()
