"""Campaign throughput: `satsim campaign` against MuJoCo's `rollout` on the same system and
the same cores (kept out of CI).

64 runs of 600 s, RK4 at 0.1 s (6000 steps each), of the satellite deploying on its hinge
springs (satellite.xml = deploy_vs_mujoco.toml), the two fold angles dispersed. MuJoCo's
rollout records the state at every step; satsim writes a row (energies and momentum
included) at every step and reduces them to final/min/max. Both run 1 thread, then every
core; satsim with its runs in SIMD lanes (`satsim`, the default) and one at a time
(`satsim1`, `--no-lanes`). First, a check that the two simulate the same system: the hinge angles of the nominal
run at t = 10 s and 600 s from `satsim run` and from MuJoCo.

    python3 -m venv /tmp/mj && /tmp/mj/bin/pip install mujoco numpy
    cargo build --release
    /tmp/mj/bin/python benches/campaign_vs_mujoco/run.py target/release/satsim
"""
import csv
import os
import resource
import subprocess
import sys
import tempfile
import time

import mujoco
import numpy as np
from mujoco import rollout

HERE = os.path.dirname(os.path.abspath(__file__))
SATSIM = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "target/release/satsim")
RUNS, NSTEP = 64, 6000
CORES = os.cpu_count() or 1


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def cpu_self():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


model = mujoco.MjModel.from_xml_path(os.path.join(HERE, "satellite.xml"))
spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
nstate = mujoco.mj_stateSize(model, spec)


def initial(a4, a5):
    d = mujoco.MjData(model)
    d.qpos[7 + 3] = a4
    d.qpos[7 + 4] = a5
    mujoco.mj_forward(model, d)
    s = np.empty(nstate)
    mujoco.mj_getState(model, d, s, spec)
    return s


# 1. The same system: nominal run, hinge angles at t = 10 s and 600 s.
with tempfile.TemporaryDirectory() as tmp:
    subprocess.run([SATSIM, "run", os.path.join(HERE, "deploy_vs_mujoco.toml"), "--out", tmp],
                   check=True, stdout=subprocess.DEVNULL)
    rows = list(csv.DictReader(open(os.path.join(tmp, "trajectory.csv"))))
state, _ = rollout.rollout(model, mujoco.MjData(model), initial(3.0, -3.0)[None, :], nstep=NSTEP)
for t in (10.0, 600.0):
    i = int(round(t / 0.1))
    row = next(r for r in rows if abs(float(r["t"]) - t) < 1e-9)
    ours = np.array([float(row[f"angle_h{j}"]) for j in range(1, 6)])
    # state[:, k] is the state after step k + 1; qpos starts after time (1 entry).
    theirs = state[0, i - 1, 1 + 7:1 + 7 + 5]
    print(f"t = {t:5.0f} s: hinge angles satsim {np.array2string(ours, precision=6)}, "
          f"MuJoCo {np.array2string(theirs, precision=6)}, max |diff| {np.abs(ours - theirs).max():.2e}")

# 2. Throughput.
rng = np.random.default_rng(1)
init = np.stack([initial(3.0 + 0.02 * rng.standard_normal(), -3.0 + 0.02 * rng.standard_normal())
                 for _ in range(RUNS)])
print(f"{RUNS} runs of 600 s, RK4 dt 0.1 ({NSTEP} steps), {CORES} cores")
print("engine   threads  wall (s)  cpu (s)  runs/s (wall)  runs/s per cpu-s")
for threads in sorted({1, CORES}):
    datas = [mujoco.MjData(model) for _ in range(threads)]
    c0, w0 = cpu_self(), time.perf_counter()
    if threads == 1:
        rollout.rollout(model, datas[0], init, nstep=NSTEP)
    else:
        with rollout.Rollout(nthread=threads) as r:
            r.rollout([model] * RUNS, datas, init, nstep=NSTEP)
    wall, cpu = time.perf_counter() - w0, cpu_self() - c0
    print(f"mujoco   {threads:7d}  {wall:8.2f}  {cpu:7.2f}  {RUNS / wall:13.1f}  {RUNS / cpu:16.1f}")
    # satsim with its runs in SIMD lanes (the default), then one run at a time per thread.
    for name, extra in (("satsim", []), ("satsim1", ["--no-lanes"])):
        with tempfile.TemporaryDirectory() as tmp:
            c0, w0 = cpu_children(), time.perf_counter()
            subprocess.run([SATSIM, "campaign", os.path.join(HERE, "deploy_vs_mujoco.toml"),
                            "--out", tmp, "--threads", str(threads)] + extra,
                           check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            wall, cpu = time.perf_counter() - w0, cpu_children() - c0
        print(f"{name:8s} {threads:7d}  {wall:8.2f}  {cpu:7.2f}  {RUNS / wall:13.1f}  {RUNS / cpu:16.1f}")
