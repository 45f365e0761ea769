"""Your controller in the loop: a 10 Hz quaternion-feedback law written in Python holds the
deploying satellite with its reaction wheels, from star-tracker and gyro readings.

    python3 examples/python/fsw_in_the_loop.py OUT_DIR [--duration S]

The scene, examples/scenes/fsw_in_the_loop.toml, is the preprint satellite deploying its
array (examples/scenes/deploy.toml) with the built-in attitude controller made discrete
(`period = 0.1`, a zero-order hold at 10 Hz), a gyro and a star tracker on the bus. Three
runs of the same law

    u = -kp * 2 sgn(q_w) q_xyz - kd * omega,   wheel commands = -u   (wheels on the bus axes)

1. built in: `satsim.run` of the scene (the law reads the true state);
2. Python, truth: the same law in a `satsim.Simulation` loop reading `sim.row()` (the built-in
   controller disabled); it must give run 1's trajectory to round-off, and the script checks
   that it does (1e-12);
3. Python, sensors: the law reading `sim.measure()`: the star tracker's quaternion and the
   gyro's rate, with their noise and the gyro's bias.

Writes OUT_DIR/fsw_in_the_loop.png (attitude error, bus rate and wheel speeds of the three)
and prints what each run achieves.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import satsim

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "examples" / "scenes"
SCENE = SCENES / "fsw_in_the_loop.toml"
BUILT_IN = "period = 0.1             # s: the flight software's rate (zero-order hold)"
KP, KD, PERIOD = 9.0, 150.0, 0.1


def scene_text(duration: float, controller: bool) -> str:
    text = SCENE.read_text()
    assert "duration = 600.0" in text and BUILT_IN in text
    text = text.replace("duration = 600.0", f"duration = {duration}", 1)
    if not controller:
        text = text.replace(BUILT_IN, BUILT_IN + "\nenabled = false", 1)
    return text


def law(q, omega):
    """The wheels' motor commands (N m) for attitude q = [w, x, y, z] and rate omega (rad/s)."""
    s = -1.0 if q[0] < 0.0 else 1.0
    u = [-KP * 2.0 * s * q[1 + i] - KD * omega[i] for i in range(3)]
    return {"wheel_x": -u[0], "wheel_y": -u[1], "wheel_z": -u[2]}


def python_loop(duration: float, from_sensors: bool) -> satsim.Trajectory:
    with satsim.Simulation(scene_text(duration, controller=False), base_dir=SCENES) as sim:
        while sim.t < duration - 1e-9:
            if from_sensors:
                m = sim.measure()
                commands = law(m["st"], m["gyro"])
            else:
                r = sim.row()
                commands = law([r["q_w"], r["q_x"], r["q_y"], r["q_z"]],
                               [r["omega_x"], r["omega_y"], r["omega_z"]])
            sim.set_inputs(commands)
            sim.advance(PERIOD)
        return sim.trajectory()


def pointing_error_arcsec(r: satsim.Trajectory) -> np.ndarray:
    """The angle of the bus attitude from the target (the identity), arcsec."""
    return np.degrees(2.0 * np.arccos(np.minimum(np.abs(r["q_w"]), 1.0))) * 3600.0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=Path)
    ap.add_argument("--duration", type=float, default=600.0)
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    built_in = satsim.run(scene_text(args.duration, controller=True), base_dir=SCENES)
    truth = python_loop(args.duration, from_sensors=False)
    sensed = python_loop(args.duration, from_sensors=True)

    worst = 0.0
    for c in built_in.columns:
        if c in truth.columns:
            scale = np.maximum(np.abs(built_in[c]), 1.0)
            worst = max(worst, float(np.max(np.abs(truth[c] - built_in[c]) / scale)))
    print(f"Python law on the truth against the built-in discrete controller: {worst:.1e}")
    if not worst <= 1e-12:
        raise SystemExit(f"the Python law does not reproduce the built-in controller ({worst:.1e})")

    t = built_in["t"]
    late = t >= 0.5 * t[-1]
    for name, r in (("built in (truth)", built_in), ("Python, truth", truth),
                    ("Python, sensors", sensed)):
        err = pointing_error_arcsec(r)
        rate = np.sqrt(r["omega_x"] ** 2 + r["omega_y"] ** 2 + r["omega_z"] ** 2)
        print(f"{name:18s} peak pointing error {err.max():9.1f} arcsec, "
              f"second half RMS {math.sqrt(np.mean(err[late] ** 2)):8.2f} arcsec, "
              f"peak rate {np.degrees(rate.max()):.4f} deg/s")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(3, 1, figsize=(8, 9), sharex=True)
    for name, r, style in (("built in (truth)", built_in, "-"), ("Python, sensors", sensed, "--")):
        ax[0].semilogy(r["t"], np.maximum(pointing_error_arcsec(r), 1e-3), style, label=name)
        for a in "xyz":
            ax[1].plot(r["t"], np.degrees(r[f"omega_{a}"]), style, label=f"{name}: {a}")
            ax[2].plot(r["t"], r[f"wheel_{a}_speed"], style, label=f"{name}: {a}")
    ax[0].set_ylabel("pointing error (arcsec)")
    ax[1].set_ylabel("bus rate (deg/s)")
    ax[2].set_ylabel("wheel speed (rad/s)")
    ax[2].set_xlabel("t (s)")
    ax[0].legend()
    ax[1].legend(fontsize=7, ncol=2)
    ax[2].legend(fontsize=7, ncol=2)
    fig.suptitle("A 10 Hz Python controller in the loop, deploying satellite")
    fig.tight_layout()
    png = args.out / "fsw_in_the_loop.png"
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")


if __name__ == "__main__":
    main()
