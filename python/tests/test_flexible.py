"""Flexible bodies from Python (contract section 14): the elastic columns flow through
satsim.run and satsim.Simulation, the modal coordinates are states (not inputs), and modes
and linearize list them after the hinge rates."""

from __future__ import annotations

import math

import numpy as np

import satsim

# A hub with a hinged panel whose beam has two modes; the panel's first mode starts deflected.
SCENE = """
duration = 1.0
[model]
[[model.body]]
name = "hub"
mass = 50.0
inertia = [[5.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 5.0]]
[[model.body]]
name = "panel"
mass = 2.0
inertia = [[0.2, 0.0, 0.0], [0.0, 0.2, 0.0], [0.0, 0.0, 0.2]]
[model.body.flexible]
beam = { root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0],
         length = 2.0, EI = 500.0, rho_A = 2.0, modes = 2 }
[[model.hinge]]
name = "h"
parent = "hub"
child = "panel"
axis = [1.0, 0.0, 0.0]
at = [0.0, 0.6, 0.0]
[initial]
hinges = { angle = [0.1], rate = [0.0] }
flexible = { panel = { eta = [0.02, 0.0] } }
[integrator]
method = "rk4"
step = 0.002
[output]
every = 0.1
plots = false
view = false
[effects.hinge_springs]
stiffness = [10.0]
"""


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def test_a_flexible_scene_steps_from_python_as_it_runs(tmp_path):
    run = satsim.run(SCENE, base_dir=tmp_path)
    for c in ["eta_panel_1", "eta_panel_2", "etadot_panel_1", "etadot_panel_2", "tip_panel"]:
        assert c in run.columns
    # The elastic columns sit right after the hinge rates.
    at = run.columns.index("rate_h")
    assert run.columns[at + 1 : at + 5] == [
        "eta_panel_1", "eta_panel_2", "etadot_panel_1", "etadot_panel_2",
    ]
    assert run["eta_panel_1"][0] == 0.02
    # phi_1(L) = 2 / sqrt(rho_A L) for a mass-normalised uniform cantilever.
    assert math.isclose(run["tip_panel"][0], 0.02 * 2.0 / math.sqrt(4.0), rel_tol=1e-12)
    with satsim.Simulation(SCENE, base_dir=tmp_path) as sim:
        assert sim.columns == run.columns
        # The modal coordinates are states: the inputs are the hinge torques only.
        assert sim.inputs == ["torque_h"]
        assert sim.row()["eta_panel_1"] == 0.02
        for dt in [0.25, 0.002, 0.748]:
            sim.advance(dt)
        r = sim.trajectory()
    assert np.array_equal(bits(r.data), bits(run.data))


def test_modes_and_linearize_list_the_elastic_states(tmp_path):
    lin = satsim.linearize(SCENE, base_dir=tmp_path)
    at = lin["states"].index("rate_h")
    assert lin["states"][at + 1 : at + 5] == [
        "eta_panel_1", "eta_panel_2", "etadot_panel_1", "etadot_panel_2",
    ]
    m = satsim.modes(SCENE, base_dir=tmp_path)
    assert any("eta_panel_1" in mode["shape"] for mode in m["modes"])
