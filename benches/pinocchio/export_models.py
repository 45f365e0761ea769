#!/usr/bin/env python3
"""Export the benchmark models to Pinocchio for the C++ harness (benches/pinocchio/harness.cpp).

Not part of the build or of CI. For each model NAME this writes into OUT_DIR:

  NAME.model.toml   the model file satsim reads (contract section 1); the satellite is a copy
                    of examples/satellite.toml, chains and binary trees equal satsim's
                    `samples::chain` / `samples::binary_tree` (crates/tree/src/samples.rs)
  NAME.state.json   the state both sides use (contract section 2)
  NAME.pin.txt      the same model as a Pinocchio model (`Model.saveToText`), built by the
                    fixture generator's mapping (tests/fixtures/pinocchio/make_fixtures.py)
  NAME.pin.state    q, v, tau and the RNEA acceleration in Pinocchio's ordering, as text:
                    "nq nv" on the first line, then one vector per line

The RNEA acceleration is `1e-3 (1 + i)` for contract coordinate i, as in `satsim bench`.

With `--aligned`, hinges whose axis is a coordinate axis become Pinocchio's specialised
JointModelRevoluteX/Y/Z instead of JointModelRevoluteUnaligned (a stronger baseline; satsim
has one generic hinge).

Usage: python3 benches/pinocchio/export_models.py OUT_DIR [--aligned] [--check SATSIM_BINARY]
With --check, Pinocchio's `aba` and `crba` on every exported model of at most 200 DOF are
compared with `satsim dynamics` on the same files (1e-9 relative), so that the timings are
known to be of the same models.
"""
import json
import os
import shutil
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tests", "fixtures", "pinocchio"))
import make_fixtures as mf  # noqa: E402  (the fixture generator: reader and Pinocchio mapping)

pin = mf.pin
sys.setrecursionlimit(10000)  # the reader walks a 1000-body chain recursively
SIZES = (10, 100, 1000)


# --- satsim's samples (crates/tree/src/samples.rs), body for body -----------------------
def sample_link(i):
    return dict(name=f"b{i}", mass=1.0, com=np.array([0.25, 0.0, 0.0]),
                inertia=np.diag([0.02, 0.08, 0.09]))


def sample_hinge(i, parent):
    axis = {0: [0.0, 0.0, 1.0], 1: [0.0, 1.0, 0.0], 2: [1.0, 0.0, 0.0]}[i % 3]
    return dict(name=f"h{i}", parent=f"b{parent}", child=f"b{i}", axis=np.array(axis),
                at=np.array([0.5, 0.0, 0.0]), child_at=np.zeros(3),
                rotation=np.array([1.0, 0.0, 0.0, 0.0]))


def sample_tree(n, parent_of):
    bodies = [sample_link(i) for i in range(n)]
    hinges = [sample_hinge(i, parent_of(i)) for i in range(1, n)]
    return bodies, hinges


# --- states --------------------------------------------------------------------------------
def bench_state(nh):
    """satsim bench's default state (crates/cli/src/commands/bench.rs, `default_state`)."""
    rate = [0.01 * (1 + k % 3) * (1 if k % 2 == 0 else -1) for k in range(nh)]
    return {"base": {"attitude": [1.0, 0.0, 0.0, 0.0],
                     "angular_velocity": [0.01, -0.02, 0.015],
                     "velocity": [0.001, 0.002, -0.001]},
            "hinges": {"angle": [0.0] * nh, "rate": rate, "torque": [0.0] * nh}}


def aligned_revolute(axis):
    axis = np.asarray(axis, dtype=float)
    for k, joint in enumerate((pin.JointModelRX, pin.JointModelRY, pin.JointModelRZ)):
        e = np.zeros(3)
        e[k] = 1.0
        if np.array_equal(axis, e):
            return joint()
    return _unaligned(axis)


_unaligned = pin.JointModelRevoluteUnaligned


def export(out, name, model_toml, state_json, aligned):
    model = mf.read_model(model_toml)
    state = mf.read_state(state_json, model)
    if aligned:
        pin.JointModelRevoluteUnaligned = aligned_revolute
    try:
        pm, perm, body_joint, hinge_joint = mf.build_pinocchio(model)
    finally:
        pin.JointModelRevoluteUnaligned = _unaligned
    q, v, tau = mf.pin_q_v_tau(model, state, pm, perm, body_joint, hinge_joint)
    acc = np.zeros(pm.nv)
    acc[perm] = 1e-3 * (1.0 + np.arange(pm.nv))
    pm.saveToText(os.path.join(out, name + ".pin.txt"))
    with open(os.path.join(out, name + ".pin.state"), "w") as f:
        f.write(f"{pm.nq} {pm.nv}\n")
        for vec in (q, v, tau, acc):
            f.write(" ".join(repr(float(x)) for x in vec) + "\n")
    return model, state, pm, perm, q, v, tau


def check(satsim, out, name, pm, perm, q, v, tau):
    """Pinocchio (from the text file just written) against `satsim dynamics`."""
    pm2 = pin.Model()
    pm2.loadFromText(os.path.join(out, name + ".pin.txt"))
    data = pm2.createData()
    acc = pin.aba(pm2, data, q, v, tau)[perm]
    M = pin.crba(pm2, data, q)
    M = (np.triu(M) + np.triu(M, 1).T)[np.ix_(perm, perm)]
    res = subprocess.run([satsim, "dynamics", "--model", os.path.join(out, name + ".model.toml"),
                          "--state", os.path.join(out, name + ".state.json")],
                         check=True, capture_output=True, text=True)
    ours = json.loads(res.stdout)
    ea = np.abs(np.array(ours["acceleration"]) - acc).max() / max(1.0, np.abs(acc).max())
    em = np.abs(np.array(ours["mass_matrix"]) - M).max() / max(1.0, np.abs(M).max())
    assert ea < 1e-9 and em < 1e-9, (name, ea, em)
    print(f"  {name:11s} dof {pm2.nv:4d}: satsim dynamics = Pinocchio "
          f"(acceleration {ea:.1e}, mass matrix {em:.1e} relative)", file=sys.stderr)


def main(argv):
    out = argv[1]
    aligned = "--aligned" in argv
    satsim = argv[argv.index("--check") + 1] if "--check" in argv else None
    os.makedirs(out, exist_ok=True)
    models = []
    for src, dst in (("satellite.toml", "satellite.model.toml"),
                     ("state.json", "satellite.state.json")):
        dst = os.path.join(out, dst)
        if os.path.exists(dst):
            os.remove(dst)
        shutil.copyfile(os.path.join(ROOT, "examples", src), dst)
    models.append("satellite")
    for n in SIZES:
        for kind, parent_of in (("chain", lambda i: i - 1), ("binary", lambda i: (i - 1) // 2)):
            name = f"{kind}{n}"
            bodies, hinges = sample_tree(n, parent_of)
            mf.write_model(os.path.join(out, name + ".model.toml"), "free", bodies, hinges,
                           header=f"satsim_tree::samples::{'chain' if kind == 'chain' else 'binary_tree'}"
                                  f"({n}, BaseKind::Free), written by export_models.py")
            with open(os.path.join(out, name + ".state.json"), "w") as f:
                json.dump(bench_state(n - 1), f)
            models.append(name)
    for name in models:
        _, _, pm, perm, q, v, tau = export(out, name, os.path.join(out, name + ".model.toml"),
                                           os.path.join(out, name + ".state.json"), aligned)
        if satsim and pm.nv <= 200:
            check(satsim, out, name, pm, perm, q, v, tau)
    print(" ".join(models))


if __name__ == "__main__":
    main(sys.argv)
