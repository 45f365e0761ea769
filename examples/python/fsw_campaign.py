"""A Monte Carlo campaign of your own flight software: the 10 Hz quaternion-feedback law of
fsw_in_the_loop.py, reading the star tracker and the gyro, flies 100 dispersed deployments.

    python3 examples/python/fsw_campaign.py OUT_DIR [--runs N] [--duration S] [--workers W]
                                                    [--resume]

The scene, examples/scenes/fsw_campaign.toml, is fsw_in_the_loop.toml with the built-in
attitude controller disabled and a `[campaign]` of 100 runs dispersing the bus inertia, the
panel hinges' stiffness, the sensors' noise and the bus's initial rates. `satsim.campaign`
draws each run's values exactly as `satsim campaign` does, and steps the drawn scene with
this module's controller at t = 0, 0.1, 0.2, ... s (zero-order hold in between):

    u = -kp * 2 sgn(q_w) q_xyz - kd * omega,   wheel commands = -u   (wheels on the bus axes)

with q from the star tracker and omega from the gyro (their noise, the gyro's bias). After
each run `metrics` reduces its trajectory to three numbers, which become columns of
runs.csv: the settling time, the RMS pointing error over the second half and the peak wheel
speed.

Writes OUT_DIR as `satsim campaign` does (runs.csv, traces.csv, summary.json,
campaign.json, the envelope plots *.svg) and OUT_DIR/fsw_campaign.png: the 5th-95th
percentile band and the median of the bus rates over time, from traces.csv. Prints how
many runs finished and the metrics' 50th, 95th and 99th percentiles.

`--runs` and `--duration` shorten the campaign (they rewrite `runs =` and `duration =` in
the scene's text); `--workers` is the number of processes (default: every core);
`--resume` continues a campaign in OUT_DIR that was stopped (Ctrl-C keeps every finished
run). The workers import this module by name (`fsw_campaign`), which is why the controller
and the metrics are at module level. The same campaign from the command line, e.g. in a
Slurm array (`--shard I/N`, then `satsim campaign merge`):

    PYTHONPATH=examples/python python3 -m satsim campaign examples/scenes/fsw_campaign.toml \\
        --controller fsw_campaign:make_fsw --period 0.1 --metrics fsw_campaign:metrics \\
        --out out/fsw-campaign
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

import numpy as np

import satsim

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "examples" / "scenes"
SCENE = SCENES / "fsw_campaign.toml"
KP, KD, PERIOD = 9.0, 150.0, 0.1        # N m/rad, N m s/rad, s: fsw_in_the_loop.py's law
SETTLED_ARCSEC = 300.0                  # "settled": the pointing error stays below this
METRICS = ("settling_time", "rms_pointing_arcsec", "peak_wheel_speed")


class Fsw:
    """The flight software under test: a quaternion-feedback (PD) law on the star tracker's
    attitude and the gyro's rate, commanding the three reaction wheels. One instance flies
    one run (it could keep state: a filter, an integrator, a mode)."""

    def __init__(self, kp: float, kd: float) -> None:
        self.kp, self.kd = kp, kd

    def step(self, t: float, meas: dict, row: dict) -> dict:
        """The wheels' motor commands (N m) at control instant t, from the sensors' latest
        readings `meas` (`row`, the true state, is there for checks; flight software has no
        truth to read)."""
        q, w = meas["st"], meas["gyro"]            # [w, x, y, z]; [x, y, z] rad/s
        s = -1.0 if q[0] < 0.0 else 1.0
        u = [-self.kp * 2.0 * s * q[1 + i] - self.kd * w[i] for i in range(3)]   # N m on the bus
        return {"wheel_x": -u[0], "wheel_y": -u[1], "wheel_z": -u[2]}


def make_fsw(run: satsim.Run) -> Fsw:
    """One controller per run. `run.index` is k, `run.seed` its sensors' noise seed and
    `run.values` its drawn values (keyed as runs.csv's columns): a law whose gains depended on
    the drawn inertia, say, would read them here."""
    return Fsw(kp=KP, kd=KD)


def pointing_error_arcsec(r) -> np.ndarray:
    """The angle of the bus attitude from the target (the identity), arcsec, at each row."""
    v = np.sqrt(r["q_x"] ** 2 + r["q_y"] ** 2 + r["q_z"] ** 2)
    return np.degrees(2.0 * np.arctan2(v, np.abs(r["q_w"]))) * 3600.0


def metrics(run: satsim.Run, trajectory: satsim.Trajectory) -> dict:
    """A run's figures of merit (each a runs.csv column), from its true trajectory:

    - settling_time (s): the first output time after which the pointing error stays below
      SETTLED_ARCSEC; the run's duration if it never settles;
    - rms_pointing_arcsec: the RMS pointing error over the second half of the run;
    - peak_wheel_speed (rad/s): the largest |speed| of any wheel.
    """
    t = trajectory["t"]
    err = pointing_error_arcsec(trajectory)
    above = np.nonzero(err >= SETTLED_ARCSEC)[0]
    if len(above) == 0:
        settling = float(t[0])
    elif above[-1] + 1 < len(t):
        settling = float(t[above[-1] + 1])
    else:
        settling = float(t[-1])                  # never settled: the run's duration
    late = t >= t[0] + 0.5 * (t[-1] - t[0])
    speed = max(float(np.max(np.abs(trajectory[f"wheel_{a}_speed"]))) for a in "xyz")
    return {
        "settling_time": settling,
        "rms_pointing_arcsec": math.sqrt(float(np.mean(err[late] ** 2))),
        "peak_wheel_speed": speed,
    }


def read_traces(path: Path) -> dict:
    """traces.csv (lines `k,column,values...`, sorted by run) as {column: (runs, samples)
    array}; `t` is one of the columns. Only finished runs have traces."""
    rows: dict = {}
    for line in path.read_text().splitlines():
        k, column, *values = line.split(",")
        rows.setdefault(column, {})[int(k)] = [float(v) for v in values]
    return {c: np.array([by_run[k] for k in sorted(by_run)]) for c, by_run in rows.items()}


def plot_envelopes(out: Path) -> Path | None:
    """The bus rates over time, from the finished runs' traces: the 5th-95th percentile band
    and the median of |omega| (log scale), and of each axis over the first 150 s. None when
    no run finished."""
    tr = read_traces(out / "traces.csv")
    if "t" not in tr:
        return None

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = tr["t"][0]
    omega = {a: np.degrees(tr[f"omega_{a}"]) for a in "xyz"}
    norm = np.sqrt(omega["x"] ** 2 + omega["y"] ** 2 + omega["z"] ** 2)
    n = norm.shape[0]

    fig, ax = plt.subplots(2, 1, figsize=(8, 7))
    lo, mid, hi = np.percentile(norm, [5, 50, 95], axis=0)
    ax[0].fill_between(t, np.maximum(lo, 1e-6), hi, color="tab:blue", alpha=0.3,
                       label="5th to 95th percentile")
    ax[0].semilogy(t, np.maximum(mid, 1e-6), color="tab:red", label="median")
    ax[0].set_ylabel("|bus rate| (deg/s)")
    ax[0].set_xlabel("t (s)")
    ax[0].legend()
    early = t <= min(150.0, t[-1])                  # the release and the capture
    for a, colour in zip("xyz", ("tab:blue", "tab:orange", "tab:green")):
        lo, mid, hi = np.percentile(omega[a][:, early], [5, 50, 95], axis=0)
        ax[1].fill_between(t[early], lo, hi, color=colour, alpha=0.25)
        ax[1].plot(t[early], mid, color=colour, label=f"omega_{a}: median, 5th-95th band")
    ax[1].set_ylabel("bus rate (deg/s)")
    ax[1].set_xlabel("t (s), the first 150 s")
    ax[1].legend(fontsize=8)
    fig.suptitle(f"A 10 Hz Python law on star tracker and gyro: {n} dispersed deployments")
    fig.tight_layout()
    png = out / "fsw_campaign.png"
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return png


def scene_text(runs: int | None, duration: float | None) -> str:
    text = SCENE.read_text()
    assert "\nruns = 100\n" in text and "\nduration = 600.0\n" in text
    if runs is not None:
        text = text.replace("\nruns = 100\n", f"\nruns = {runs}\n", 1)
    if duration is not None:
        text = text.replace("\nduration = 600.0\n", f"\nduration = {duration}\n", 1)
    return text


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=Path)
    ap.add_argument("--runs", type=int, help="runs (default: the scene's 100)")
    ap.add_argument("--duration", type=float, help="s (default: the scene's 600)")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                    help="processes (default: every core)")
    ap.add_argument("--resume", action="store_true", help="continue a stopped campaign in OUT")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    # The workers unpickle the controller factory and the metrics by module and name: take
    # them from the module `fsw_campaign` (this file's folder is on sys.path when it runs as
    # a script), not from `__main__`.
    import fsw_campaign

    if args.runs is None and args.duration is None:
        scene, base_dir = SCENE, None
    else:
        scene, base_dir = scene_text(args.runs, args.duration), SCENES
    try:
        res = satsim.campaign(scene, base_dir=base_dir, controller=fsw_campaign.make_fsw,
                              period=PERIOD, metrics=fsw_campaign.metrics, out=args.out,
                              workers=args.workers, resume=args.resume)
    except KeyboardInterrupt as e:      # Ctrl-C: the finished runs are in OUT/runs.csv
        print(f"{e} (here: the same command with --resume)", file=sys.stderr)
        raise SystemExit(130) from None

    table = res.table                       # runs.csv, as a satsim.CampaignResult
    ok = table.ok
    print(f"{len(table)} runs: {int(ok.sum())} ok, {int((~ok).sum())} failed")
    for status, message in zip(table.status, table.messages):
        if status != "ok":
            print(f"  failed: {message}")
    # The metrics' columns, and the peak bus rate from the min_/max_ statistics of every run.
    columns = {name: table[name] for name in METRICS}
    columns["peak_bus_rate_deg_s"] = np.degrees(np.max(
        [np.maximum(np.abs(table[f"min_omega_{a}"]), np.abs(table[f"max_omega_{a}"]))
         for a in "xyz"], axis=0))
    print(f"{'over the ok runs':24s} {'p50':>10s} {'p95':>10s} {'p99':>10s}")
    for name, values in columns.items():
        if ok.any():
            p = np.percentile(values[ok], [50, 95, 99])      # summary.json's percentiles
            print(f"{name:24s} {p[0]:10.4g} {p[1]:10.4g} {p[2]:10.4g}")

    png = plot_envelopes(args.out)
    print(f"wrote {args.out}: runs.csv, summary.json, traces.csv, envelope_*.svg"
          + ("" if png is None else f" and {png.name}"))


if __name__ == "__main__":
    main()
