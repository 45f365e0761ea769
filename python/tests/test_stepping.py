"""satsim.Simulation: a scene stepped from Python (contract section 13)."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

import satsim
from conftest import SCENES

DEPLOY = SCENES / "deploy.toml"
KD_LINE = "kd = 150.0               # N m s/rad"


def deploy_text(duration: float, attitude: str = "") -> str:
    text = DEPLOY.read_text()
    assert "duration = 300.0" in text and KD_LINE in text
    text = text.replace("duration = 300.0", f"duration = {duration}", 1)
    return text.replace(KD_LINE, "kd = 150.0\n" + attitude, 1)


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def test_pieces_of_whole_steps_give_the_run_to_the_last_bit():
    text = deploy_text(60.0)
    run = satsim.run(text, base_dir=SCENES)
    rng = random.Random(5)
    events = []
    with satsim.Simulation(text, base_dir=SCENES) as sim:
        assert sim.t == 0.0
        assert sim.columns == run.columns
        while sim.t < 60.0:
            events += sim.advance(min(rng.randint(1, 300) * 0.01, 60.0 - sim.t))
        r = sim.trajectory()
    assert isinstance(r, satsim.Trajectory)
    assert r.columns == run.columns
    assert np.array_equal(bits(r.data), bits(run.data))
    assert any(e == "hinge_stops" for _, e, _ in events), events


def test_row_inputs_and_measure():
    with satsim.Simulation(DEPLOY) as sim:
        row = sim.row()
        assert list(row) == sim.columns
        assert row["t"] == 0.0 and row["angle_h4"] == 3.14159
        assert sim.inputs == [
            "torque_h1",
            "torque_h2",
            "torque_h3",
            "torque_h4",
            "torque_h5",
            "wheel_x",
            "wheel_y",
            "wheel_z",
        ]
        assert sim.measure() == {}
        sim.advance(0.5)
        assert sim.t == 0.5
        assert sim.row()["t"] == 0.5
        assert len(sim.trajectory()) == 1  # rows every 1 s: only t = 0 so far


def test_bad_input_raises_and_changes_nothing():
    with satsim.Simulation(DEPLOY) as sim:
        sim.set_inputs({"wheel_x": 0.01})
        sim.advance(0.3)
        t, row, n = sim.t, sim.row(), len(sim.trajectory())
        with pytest.raises(satsim.SatsimError, match="wheel_q"):
            sim.set_inputs({"wheel_q": 1.0})
        with pytest.raises(satsim.SatsimError, match="wheel_x"):
            sim.set_inputs({"wheel_y": 0.2, "wheel_x": math.nan})
        with pytest.raises(satsim.SatsimError, match="torque_h4"):
            sim.set_inputs({"torque_h4": math.inf})
        with pytest.raises(satsim.SatsimError, match="must be a number"):
            sim.set_inputs({"torque_h4": "a lot"})
        # A number written as a string is not a number; nor is the mapping None.
        with pytest.raises(satsim.SatsimError, match="must be a number"):
            sim.set_inputs({"wheel_x": "1"})
        with pytest.raises(satsim.SatsimError, match="mapping"):
            sim.set_inputs(None)
        for dt in (0.0, -1.0, math.nan, math.inf):
            with pytest.raises(satsim.SatsimError, match="dt"):
                sim.advance(dt)
        assert sim.t == t and sim.row() == row and len(sim.trajectory()) == n
        # wheel_y was not set by the refused call.
        with satsim.Simulation(DEPLOY) as ref:
            ref.set_inputs({"wheel_x": 0.01})
            ref.advance(0.3)
            ref.advance(0.4)
            sim.advance(0.4)
            assert sim.row() == ref.row()
    with pytest.raises(satsim.SatsimError, match="closed"):
        sim.advance(0.1)


def test_a_python_controller_mirroring_the_discrete_attitude_controller_gives_its_trajectory():
    """deploy.toml's attitude law, `period = 0.1`, against the same law in Python: the
    target is the identity, so the error quaternion is the attitude; the wheels lie along the
    bus axes, so their commands are `-u`."""
    builtin = satsim.run(deploy_text(30.0, "period = 0.1"), base_dir=SCENES)
    kp, kd = 9.0, 150.0
    with satsim.Simulation(deploy_text(30.0, "enabled = false"), base_dir=SCENES) as sim:
        while sim.t < 30.0 - 1e-9:
            r = sim.row()
            s = -1.0 if r["q_w"] < 0.0 else 1.0
            u = [
                -kp * 2.0 * s * r["q_" + a] - kd * r["omega_" + a] for a in ("x", "y", "z")
            ]
            sim.set_inputs({"wheel_x": -u[0], "wheel_y": -u[1], "wheel_z": -u[2]})
            sim.advance(0.1)
        mine = sim.trajectory()
    assert len(mine) == len(builtin)
    common = [c for c in mine.columns if c in builtin]
    assert len(common) > 20
    for c in common:
        scale = np.maximum(np.abs(builtin[c]), 1.0)
        worst = np.max(np.abs(mine[c] - builtin[c]) / scale)
        assert worst <= 1e-12, (c, worst)


def test_out_writes_what_satsim_run_writes(tmp_path):
    out = tmp_path / "fsw"
    with satsim.Simulation(deploy_text(3.0), out, base_dir=SCENES) as sim:
        while sim.t < 3.0:
            sim.advance(0.5)
        # Streamed: the rows so far are in the file before close().
        assert (out / "trajectory.csv").exists()
    assert sim.closed
    r = satsim.read_trajectory(out / "trajectory.csv")
    assert np.array_equal(bits(r.data), bits(sim.trajectory().data))
    assert (out / "events.csv").exists() and (out / "view.html").exists()


def test_a_bad_scene_or_period_is_an_error_naming_it():
    with pytest.raises(satsim.SatsimError, match="period"):
        satsim.Simulation(deploy_text(3.0, "period = 0.0"), base_dir=SCENES)
    with pytest.raises(satsim.SatsimError):
        satsim.Simulation(SCENES / "no_such_scene.toml")


THRUSTER_SCENE = """
duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 50.0
inertia = [[4.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 6.0]]
[integrator]
method = "rk4"
step = 0.01
[output]
every = 0.1
plots = false
view = false
[effects.thrusters]
period = 0.1
[[effects.thrusters.thruster]]
name = "roll"
body = "bus"
at = [0.0, 0.5, 0.0]
direction = [0.0, 0.0, 1.0]
thrust = 2.0
duty = DUTY
"""


def test_a_thruster_duty_set_from_python_acts_as_the_same_constant_duty():
    # r x F = (0.5 m) y x (2 N) z = (1, 0, 0) N m: h_x grows by 1 N m per second fired.
    run = satsim.run(THRUSTER_SCENE.replace("DUTY", "0.3"))
    with satsim.Simulation(THRUSTER_SCENE.replace("DUTY", "0.0")) as sim:
        assert sim.inputs == ["thrust_roll"]
        sim.set_inputs({"thrust_roll": 0.3})
        for _ in range(10):
            sim.advance(0.1)
        r = sim.trajectory()
        assert r.columns == run.columns
        assert np.array_equal(bits(r.data), bits(run.data))
        assert abs(sim.row()["h_x"] - 10 * 0.3 * 0.1) < 1e-14
        with pytest.raises(satsim.SatsimError, match="thrust_roll"):
            sim.set_inputs({"thrust_roll": 1.5})


def test_rows_kept_are_bounded_by_max_rows_and_a_long_dt_is_refused_at_once():
    # advance(1e9) used to list 1e10 output times (gigabytes) before integrating.
    text = THRUSTER_SCENE.replace("DUTY", "0.0")
    with satsim.Simulation(text) as sim:
        assert sim.max_rows == satsim.Simulation.MAX_ROWS == 1_000_000
        with pytest.raises(satsim.SatsimError, match=r"dt = 1e9 s would record about 10000000000 rows .*`max_rows`"):
            sim.advance(1e9)
        assert sim.t == 0.0 and len(sim.trajectory().data) == 1
        sim.advance(0.5)
        assert len(sim.trajectory().data) == 6
    with satsim.Simulation(text, max_rows=3) as sim:
        sim.advance(0.2)
        assert len(sim.trajectory().data) == 3
        with pytest.raises(satsim.SatsimError, match="more than the 0 left of the limit of 3 rows kept"):
            sim.advance(0.1)
        assert sim.t == pytest.approx(0.2, abs=1e-15)
        sim.advance(0.05)  # no output time in (0.2, 0.25]: nothing to keep
        assert len(sim.trajectory().data) == 3
    for bad in (0, -1, 1.5, True, "3"):
        with pytest.raises(satsim.SatsimError, match="max_rows"):
            satsim.Simulation(text, max_rows=bad)


def test_advance_goes_on_past_the_scenes_end_on_the_same_grid():
    text = THRUSTER_SCENE.replace("DUTY", "0.0")
    with satsim.Simulation(text) as sim:
        assert sim.t_end == 1.0
        sim.advance(1.5)
        assert sim.t == pytest.approx(1.5, abs=1e-15)
        t = sim.trajectory()["t"]
        assert len(t) == 16 and t[10] == 1.0 and t[-1] == pytest.approx(1.5, abs=1e-15)


def test_steps_held_by_a_stiff_motion_warn_at_close_as_the_command_line_does():
    """The stiff hinge under DP5(4), advanced a second at a time: the integrator's steps sit
    at the method's stability limit (about 7 ms), and `close` warns in `satsim run`'s words.
    Advanced in pieces shorter than the limit, the pieces are the steps: no warning."""
    text = (SCENES / "stiff_hinge.toml").read_text()
    text = text.replace("duration = 100.0", "duration = 10.0")
    text = text.replace('method = "radau5"', 'method = "dp54"')
    assert 'method = "dp54"' in text
    sim = satsim.Simulation(text, base_dir=SCENES)
    for _ in range(10):
        sim.advance(1.0)
    with pytest.warns(UserWarning, match=r"held the steps; `integrator.method = \"radau5\"`"):
        sim.close()
    import warnings

    sim = satsim.Simulation(text, base_dir=SCENES)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for _ in range(1700):
            sim.advance(0.006)
        sim.close()


def test_work_counts_the_steps_and_the_advances_keep_radaus_jacobian():
    """`work` sums the integrator's counts over the advances: RK4 at 0.01 s takes its 1000
    steps in 10 s of pieces; the flexible deployment under Radau IIA at 10 Hz takes a
    Jacobian only where a latch or a slow Newton iteration asks, not one a piece."""
    with satsim.Simulation(deploy_text(10.0), base_dir=SCENES) as sim:
        for _ in range(100):
            sim.advance(0.1)
        w = sim.work
    assert set(w) == {"rhs_evals", "steps_accepted", "steps_rejected", "steps_capped",
                      "jacobian_evals", "jacobian_updates", "lu_decompositions"}
    # A step split at an event (the wheels' friction) counts twice: 1004. RK4's steps are
    # its own, never cut to a piece's end.
    assert 1000 <= w["steps_accepted"] < 1010 and w["jacobian_evals"] == 0, w
    assert w["steps_capped"] == 0, w
    assert w["rhs_evals"] >= 4 * 1000, w
    flexible = SCENES.parent / "flexible_array.toml"
    text = flexible.read_text().replace("duration = 300.0", "duration = 10.0")
    with satsim.Simulation(text, base_dir=flexible.parent) as sim:
        assert sim.work["rhs_evals"] == 0
        for _ in range(100):
            sim.advance(0.1)
        w = sim.work
    assert w["steps_accepted"] >= 100, w
    # Radau IIA's steps are cut to each piece's end: one capped step a piece, the rest set
    # by its error control. A latch inside a capped step (h5 at 4.46 s, h4 at 9.53 s) cuts
    # it there, and the piece's rest is capped again (101 today).
    assert 100 <= w["steps_capped"] <= 102 and w["steps_accepted"] > 300, w
    # The one run of these 10 s takes 5 by differences and 9 updated through the mass matrix
    # (`satsim run`: the latches, Newton slowing while the panels swing); a piece started
    # afresh would take one each, 100.
    assert 1 <= w["jacobian_evals"] <= 20, w
    assert 1 <= w["jacobian_updates"] <= 20, w
    assert w["lu_decompositions"] >= 1, w
