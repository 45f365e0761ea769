"""The errors of `satsim run` trajectories against a reference trajectory, over the whole run:
the largest hinge-angle error at any output time, the attitude's, the rates', and the flexible
panels' tip deflections' where there are any. What the accuracy page's flexible-deployment
target is measured with (the sweep of `satsim accuracy` samples at the scene's output
interval and folds all states into one error; this looks at the hinge angles alone, at
whatever interval the runs wrote). Not run by cargo or CI.

    satsim run SCENE --set output.every=0.1 --set integrator.method=dop853 \
        --set integrator.rtol=1e-12 --set integrator.atol=1e-12 --out ref
    satsim run SCENE --set output.every=0.1 --out run
    python benches/accuracy/hinge_errors.py ref run [run ...]

Needs numpy.
"""

import csv
import sys

import numpy as np


def load(folder):
    with open(f"{folder}/trajectory.csv") as f:
        rows = csv.reader(f)
        head = next(rows)
        return head, np.array([[float(x) for x in r] for r in rows])


def rotation_angle(a, b):
    """The angle of conj(a) ⊗ b, Hamilton quaternions [w, x, y, z] per row."""
    w = (a * b).sum(1)
    x = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0] - a[:, 2] * b[:, 3] + a[:, 3] * b[:, 2]
    y = a[:, 0] * b[:, 2] + a[:, 1] * b[:, 3] - a[:, 2] * b[:, 0] - a[:, 3] * b[:, 1]
    z = a[:, 0] * b[:, 3] - a[:, 1] * b[:, 2] + a[:, 2] * b[:, 1] - a[:, 3] * b[:, 0]
    return 2 * np.arctan2(np.sqrt(x * x + y * y + z * z), np.abs(w))


def main(ref_dir, runs):
    head, ref = load(ref_dir)
    col = {n: i for i, n in enumerate(head)}
    angles = [i for n, i in col.items() if n.startswith("angle_")]
    rates = [i for n, i in col.items() if n.startswith(("rate_", "omega_"))]
    quat = [col[n] for n in ("q_w", "q_x", "q_y", "q_z")]
    tips = [i for n, i in col.items() if n.startswith("tip_")]
    for run in runs:
        _, d = load(run)
        n = min(len(d), len(ref))
        if not np.allclose(d[:n, 0], ref[:n, 0]):
            sys.exit(f"{run}: its output times are not the reference's")
        a, r = d[:n], ref[:n]
        ea = np.abs(a[:, angles] - r[:, angles]).max(1)
        er = np.abs(a[:, rates] - r[:, rates]).max(1)
        eq = rotation_angle(r[:, quat], a[:, quat])
        line = (
            f"{run}: hinge angles largest {ea.max():.1e} rad (final {ea[-1]:.1e}); "
            f"attitude largest {eq.max():.1e} rad; rates largest {er.max():.1e} rad/s"
        )
        if tips:
            et = np.abs(a[:, tips] - r[:, tips]).max() * 1e3
            line += f"; tip deflections largest error {et:.2f} mm"
        print(line)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
