"""Simulation.measure(): the scene's sensors' readings by name and by column (contract
section 13), and the seed= keyword that replaces the scene's [sensors] seed."""

from __future__ import annotations

import pytest

import satsim

SCENE = """
duration = 1.0

[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 12.0, 0.0], [0.0, 0.0, 8.0]]

[initial]
base = { attitude = [0.9, 0.1, -0.3, 0.3], angular_velocity = [0.05, -0.02, 0.03] }

[integrator]
method = "rk4"
step = 0.01

[output]
every = 0.1
plots = false
view = false

[sensors]
seed = 4
[[sensors.gyro]]
name = "gyro"
body = "bus"
period = 0.1
NOISE
[[sensors.star_tracker]]
name = "st"
body = "bus"
period = 0.1
"""


def scene(noise: str = "") -> str:
    return SCENE.replace("NOISE", noise)


def test_measure_gives_each_reading_by_name_and_by_column():
    with satsim.Simulation(scene()) as sim:
        m = sim.measure()
        row = sim.row()
        # Without noise: the truth at the start (the first sample is at t0).
        assert m["gyro"] == [row["omega_x"], row["omega_y"], row["omega_z"]]
        assert len(m["st"]) == 4 and m["st"][0] >= 0.0
        sign = 1.0 if row["q_w"] >= 0.0 else -1.0
        assert m["st"] == [sign * row[c] for c in ("q_w", "q_x", "q_y", "q_z")]
        sim.advance(0.25)
        m = sim.measure()
        # Held since the sample at 0.2 s: the column values of the row at 0.2 s.
        r = sim.trajectory()
        at = list(r.t).index(0.2)
        for c in ("gyro_x", "gyro_y", "gyro_z", "st_q_w", "st_q_x", "st_q_y", "st_q_z"):
            assert m[c] == r[c][at]
        assert m["gyro"] == [m["gyro_x"], m["gyro_y"], m["gyro_z"]]
        assert set(m) == {"gyro", "st", "gyro_x", "gyro_y", "gyro_z",
                          "st_q_w", "st_q_x", "st_q_y", "st_q_z"}


def readings(seed=None):
    with satsim.Simulation(scene("noise_density = 1e-3"), seed=seed) as sim:
        out = [sim.measure()["gyro"]]
        for _ in range(3):
            sim.advance(0.1)
            out.append(sim.measure()["gyro"])
    return out


def test_seed_replaces_the_scenes_seed():
    assert readings() == readings(4)
    assert readings(5) == readings(5)
    assert readings(5) != readings(4)
    with pytest.raises(satsim.SatsimError):
        satsim.Simulation(scene(), seed=-1)


def test_a_scene_without_sensors_measures_nothing():
    text = SCENE.split("[sensors]")[0]
    with satsim.Simulation(text, seed=3) as sim:
        assert sim.measure() == {}
