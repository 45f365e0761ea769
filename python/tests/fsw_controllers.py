"""Controllers for the tests of campaigns stepped by Python flight software
(test_fsw_campaign.py): at module level, so that worker processes can import them."""

from __future__ import annotations

import math
import time

#: What the factory saw, in this process: (index, seed, values) per run.
SEEN = []


class Nothing:
    """Leaves the inputs as they are: the campaign is `satsim campaign`'s."""

    def step(self, t, meas, row):
        return {}


def nothing(run):
    return Nothing()


def recording(run):
    SEEN.append((run.index, run.seed, dict(run.values)))
    return Nothing()


class Pd:
    """The flight-software example's law on the truth: wheels hold the bus still."""

    def step(self, t, meas, row):
        s = -1.0 if row["q_w"] < 0.0 else 1.0
        u = [-9.0 * 2.0 * s * row[f"q_{a}"] - 150.0 * row[f"omega_{a}"] for a in "xyz"]
        return {"wheel_x": -u[0], "wheel_y": -u[1], "wheel_z": -u[2]}


def pd(run):
    return Pd()


class Raises:
    def __init__(self, index):
        self.index = index

    def step(self, t, meas, row):
        if self.index == 3 and t >= 0.5:
            raise ValueError(f"boom in run {self.index}")
        return {}


def raises_at_run_3(run):
    return Raises(run.index)


class Bad:
    def __init__(self, index):
        self.index = index

    def step(self, t, meas, row):
        if self.index == 1:
            return {"wheel_q": 0.1}
        if self.index == 2:
            return {"wheel_x": math.nan}
        if self.index == 4:
            return None
        return {}


def bad(run):
    return Bad(run.index)


def factory_raises(run):
    if run.index == 2:
        raise RuntimeError("no controller for run 2")
    return Nothing()


class Slow:
    def step(self, t, meas, row):
        time.sleep(0.002)
        return {}


def slow(run):
    return Slow()


def settling(run, trajectory):
    """Two metrics from the trajectory: the largest bus rate and the last hinge angle."""
    w = max(math.sqrt(x * x + y * y + z * z) for x, y, z in
            zip(trajectory["omega_x"], trajectory["omega_y"], trajectory["omega_z"]))
    return {"peak_rate": w, "last_h4": float(trajectory["angle_h4"][-1])}
