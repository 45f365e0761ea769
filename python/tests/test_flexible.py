"""Flexible bodies from Python (contract section 14): the elastic columns flow through
satsim.run and satsim.Simulation, the modal coordinates are states (not inputs), modes
and linearize list them after the hinge rates, and satsim.Model reads a flexible model: its
dynamics (the command line's bits) and its coupled modes (a cantilever's are
Euler-Bernoulli's)."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import warnings

import numpy as np
import pytest

import satsim
from conftest import EXAMPLES

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


def test_a_beam_bent_beyond_its_modal_model_is_a_warning_and_a_campaign_column(tmp_path):
    # As shipped, the tip starts at 2 cm of the 2 m beam: no warning.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        satsim.run(SCENE, base_dir=tmp_path)
    # Started at 0.3 m (15 % of the length), the tip is past a tenth from the first step.
    bent = SCENE.replace("eta = [0.02, 0.0]", "eta = [0.3, 0.0]")
    with pytest.warns(UserWarning, match="body `panel`'s tip passed a tenth of its 2 m length"):
        run = satsim.run(bent, base_dir=tmp_path)
    assert abs(run["tip_panel"][0]) > 0.2
    # Stepped, the warning comes when the simulation is closed (once).
    sim = satsim.Simulation(bent, base_dir=tmp_path)
    sim.advance(0.5)
    with pytest.warns(UserWarning, match="body `panel`'s tip passed a tenth"):
        sim.close()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim.close()
    # A campaign of it gives each run's peak over every step, as a fraction of the length.
    text = bent + """
[campaign]
runs = 2
seed = 1
[[campaign.disperse]]
key = "model.body.0.mass"
uniform = { low = -1.0, high = 1.0 }
"""
    with pytest.warns(UserWarning, match="2 of the 2 finished runs bent a flexible body past"):
        c = satsim.campaign(text, base_dir=tmp_path)
    assert c.columns[-2:] == ["peak_deflection_panel", "stability_held"]
    peaks = c["peak_deflection_panel"]
    assert (peaks > 0.1).all() and (peaks < 1.0).all(), peaks


# --- satsim.Model of a model with flexible bodies: dynamics and modes ---------------------

FLEXIBLE_SATELLITE = EXAMPLES / "satellite_flexible.toml"

# A state of the flexible satellite: every panel deformed or vibrating, torques on h3-h5.
FLEX_STATE = {
    "base": {"angular_velocity": [0.01, -0.02, 0.015], "velocity": [0.1, 0.0, -0.2]},
    "hinges": {
        "angle": [0.3, -0.2, 0.1, 1.2, -1.0],
        "rate": [0.1, 0.2, -0.1, 0.5, -0.4],
        "torque": [0.0, 0.0, 0.3, -0.5, 0.4],
    },
    "flexible": {
        "panel1": {"eta": [0.02, -0.004, 0.001], "etadot": [0.1, 0.02, -0.01]},
        "panel2": {"eta": [-0.01, 0.003, 0.0]},
        "panel3": {"etadot": [-0.05, 0.0, 0.03]},
    },
}


def test_a_flexible_model_has_the_rigid_dof_plus_its_modes():
    flex = satsim.Model.from_file(FLEXIBLE_SATELLITE)
    rigid = satsim.Model.from_file(EXAMPLES / "satellite.toml")
    assert flex.flexible == {"panel1": 3, "panel2": 3, "panel3": 3}
    assert rigid.flexible == {} and rigid.modal_frequencies == {}
    assert flex.dof == rigid.dof + 9 == 20
    assert flex.body_names == rigid.body_names and flex.hinge_names == rigid.hinge_names
    assert math.isclose(flex.total_mass, rigid.total_mass, rel_tol=1e-12)
    # Each strip (EI = 100, rho_A = 10, L = 1): 1.8751^2 sqrt(EI / (rho_A L^4)) / 2 pi.
    hz = flex.modal_frequencies
    assert list(hz) == ["panel1", "panel2", "panel3"]
    for f in hz.values():
        assert f.shape == (3,)
        assert math.isclose(f[0], 3.516015268 * math.sqrt(10.0) / (2 * math.pi), rel_tol=1e-6)
    # from_toml reads the same model.
    text = FLEXIBLE_SATELLITE.read_text()
    assert satsim.Model.from_toml(text).flexible == flex.flexible


def test_a_flexible_models_dynamics_solve_their_equation_and_equal_the_command_line(cli, tmp_path):
    m = satsim.Model.from_file(FLEXIBLE_SATELLITE)
    d = m.dynamics(FLEX_STATE)
    assert d["dof"] == 20
    M, a, b = d["mass_matrix"], d["acceleration"], d["bias"]
    assert M.shape == (20, 20) and a.shape == b.shape == (20,)
    np.testing.assert_array_equal(M, M.T)
    tau = np.zeros(20)
    tau[6:11] = FLEX_STATE["hinges"]["torque"]
    scale = max(np.abs(M @ a).max(), np.abs(b).max())
    assert np.abs(M @ a + b - tau).max() <= 1e-10 * scale
    # v = [omega, v, rates, etadot]: T = v' M v / 2.
    f = FLEX_STATE["flexible"]
    etadot = f["panel1"]["etadot"] + [0.0, 0.0, 0.0] + f["panel3"]["etadot"]
    v = np.concatenate([
        FLEX_STATE["base"]["angular_velocity"], FLEX_STATE["base"]["velocity"],
        FLEX_STATE["hinges"]["rate"], etadot,
    ])
    assert math.isclose(d["kinetic_energy"], 0.5 * v @ M @ v, rel_tol=1e-12)
    # The command line, on the same state file, to the last bit.
    path = tmp_path / "flex_state.json"
    path.write_text(json.dumps(FLEX_STATE))
    out = subprocess.run(
        [cli, "dynamics", "--model", FLEXIBLE_SATELLITE, "--state", path],
        check=True, capture_output=True, text=True,
    ).stdout
    want = json.loads(out)
    got = m.dynamics(path)
    assert got["dof"] == want["dof"] == 20
    for key in ("mass_matrix", "bias", "acceleration", "kinetic_energy"):
        np.testing.assert_array_equal(bits(got[key]), bits(want[key]), err_msg=key)


def test_an_undeformed_flexible_model_is_close_to_its_rigid_twin():
    # satellite_flexible.toml differs from satellite.toml by the bending only (and the
    # rounding of the panels' rigid inertia, 0.834 for 10/12): at eta = 0, the rigid block
    # of the mass matrix is the rigid model's.
    flex = satsim.Model.from_file(FLEXIBLE_SATELLITE).dynamics(EXAMPLES / "state.json")
    rigid = satsim.Model.from_file(EXAMPLES / "satellite.toml").dynamics(EXAMPLES / "state.json")
    M = rigid["mass_matrix"]
    assert np.abs(flex["mass_matrix"][:11, :11] - M).max() < 1e-3 * np.abs(M).max()
    assert math.isclose(flex["kinetic_energy"], rigid["kinetic_energy"], rel_tol=1e-5)


def test_a_flexible_model_refuses_a_wrong_elastic_state_naming_it(tmp_path):
    m = satsim.Model.from_file(FLEXIBLE_SATELLITE)
    bad = {"hinges": {"angle": [0.0] * 5, "rate": [0.0] * 5},
           "flexible": {"panel2": {"eta": [0.1, 0.2]}}}
    with pytest.raises(satsim.SatsimError, match=r"flexible\.panel2\.eta: expected 3 values"):
        m.dynamics(bad)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(bad, indent=2))
    with pytest.raises(satsim.SatsimError) as e:
        m.dynamics(path)
    assert str(e.value).startswith(f"{path}:") and "expected 3 values" in str(e.value)
    with pytest.raises(satsim.SatsimError, match="not flexible"):
        m.modes({"flexible": {"bus": {"eta": [1.0]}}})


# (beta_n L)^2, the roots of cos x cosh x = -1 squared: a clamped-free beam's omega_n with
# EI = rho_A = L = 1.
CLAMPED = [3.516015268, 22.03449187, 61.69721435]


def test_a_cantilever_models_modes_are_euler_bernoullis():
    m = satsim.Model.from_toml("""
[base]
kind = "fixed"
[[body]]
name = "beam"
mass = 0.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
[body.flexible]
beam = { root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0],
         length = 1.0, EI = 1.0, rho_A = 1.0, modes = 3 }
""")
    assert m.dof == 3 and m.flexible == {"beam": 3}
    modes = m.modes({})
    np.testing.assert_allclose(modes["omega"], CLAMPED, rtol=1e-4)
    np.testing.assert_allclose(modes["frequencies_hz"], modes["omega"] / (2 * math.pi))
    np.testing.assert_allclose(m.modal_frequencies["beam"], modes["frequencies_hz"], rtol=1e-12)
    # A cantilever alone: M = 1, its own modes are the shapes.
    np.testing.assert_allclose(np.abs(modes["shapes"]), np.eye(3), atol=1e-12)


def test_a_flexible_models_coupled_modes_solve_k_x_equals_omega2_m_x():
    m = satsim.Model.from_file(FLEXIBLE_SATELLITE)
    modes = m.modes(FLEX_STATE)
    w, X = modes["omega"], modes["shapes"]
    assert w.shape == (9,) and X.shape == (20, 9)
    assert np.all(np.diff(w) >= 0) and w[0] > 0
    M = m.dynamics(FLEX_STATE)["mass_matrix"]
    K = np.zeros((20, 20))
    clamped = np.concatenate(list(m.modal_frequencies.values())) * 2 * math.pi
    K[11:, 11:] = np.diag(clamped**2)
    np.testing.assert_allclose(X.T @ M @ X, np.eye(9), atol=1e-9)
    for k in range(9):
        r = K @ X[:, k] - w[k] ** 2 * (M @ X[:, k])
        assert np.abs(r).max() <= 1e-8 * w[k] ** 2
    # A rigid model has none.
    rigid = satsim.Model.from_file(EXAMPLES / "satellite.toml").modes(EXAMPLES / "state.json")
    assert rigid["omega"].shape == (0,) and rigid["shapes"].shape == (11, 0)


# A hub with a hinged panel whose modes come from the committed example modes file, named
# relative to examples/.
MODES_FILE_MODEL = """
[[body]]
name = "hub"
mass = 50.0
inertia = [[5.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 5.0]]
[[body]]
name = "panel"
mass = 0.0
[body.flexible]
modes_file = "modes/panel_beam_modes.toml"
[[hinge]]
name = "h"
parent = "hub"
child = "panel"
axis = [1.0, 0.0, 0.0]
at = [0.0, 0.5, 0.0]
"""


def test_from_toml_reads_a_relative_modes_file_from_base_dir(tmp_path, monkeypatch):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    # Without base_dir the current directory, which has no modes/: refused, naming the key.
    with pytest.raises(satsim.SatsimError,
                       match=r"^<model text>:10: .*`modes_file` = \"modes/panel_beam_modes.toml\""):
        satsim.Model.from_toml(MODES_FILE_MODEL)
    # With base_dir (a str or a path, relative or not): read from there.
    for base in (EXAMPLES, str(EXAMPLES), os.path.relpath(EXAMPLES)):
        m = satsim.Model.from_toml(MODES_FILE_MODEL, base_dir=base)
        assert m.flexible == {"panel": 3}
        assert m.origin == os.path.join(os.fspath(base), "<model text>")
    # The file's frequencies (frequencies_hz of examples/modes/panel_beam_modes.toml).
    assert np.array_equal(m.modal_frequencies["panel"],
                          [1.398978024920942, 8.767245627583467, 24.54854162229218])
    # The same model, to the bit, as from_file on the text saved where the modes file is.
    (tmp_path / "modes").mkdir()
    shutil.copy(EXAMPLES / "modes" / "panel_beam_modes.toml", tmp_path / "modes")
    (tmp_path / "panel.toml").write_text(MODES_FILE_MODEL)
    f = satsim.Model.from_file(tmp_path / "panel.toml")
    state = {"base": {"angular_velocity": [0.01, -0.02, 0.03]},
             "hinges": {"angle": [0.3], "rate": [0.1]},
             "flexible": {"panel": {"eta": [0.01, -0.002, 0.0], "etadot": [0.1, 0.0, 0.0]}}}
    a, b = m.dynamics(state), f.dynamics(state)
    for key in ("mass_matrix", "bias", "acceleration"):
        assert np.array_equal(bits(a[key]), bits(b[key])), key
    # A name stands for a file in base_dir; an error there names it so.
    g = satsim.Model.from_toml(MODES_FILE_MODEL, "sat/panel.toml", base_dir=tmp_path)
    assert g.origin == os.path.join(str(tmp_path), "panel.toml")
    with pytest.raises(satsim.SatsimError, match=r"nowhere.<model text>:10: .*cannot read it"):
        satsim.Model.from_toml(MODES_FILE_MODEL, base_dir=tmp_path / "nowhere")
    # The default is still the current directory.
    monkeypatch.chdir(EXAMPLES)
    assert satsim.Model.from_toml(MODES_FILE_MODEL).flexible == {"panel": 3}


# A free hub with a panel whose modes come from the contract beam's modes file (its first mode
# at 2 % of the tip's 2 m), undamped: RK4 at 5 ms is inside its 65.8 Hz mode's stability limit
# (6.85 ms) yet drains a third of the energy in a second.
MODES_FILE_SCENE = """
duration = 1.0
[model]
[[model.body]]
name = "hub"
mass = 50.0
inertia = [[5.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 5.0]]
[[model.body]]
name = "panel"
mass = 0.0
[model.body.flexible]
modes_file = "panel_beam_modes.toml"
stiffening = false
[[model.hinge]]
name = "h"
parent = "hub"
child = "panel"
axis = [1.0, 0.0, 0.0]
at = [0.0, 0.5, 0.0]
[initial]
hinges = { angle = [0.0], rate = [0.0] }
flexible = { panel = { eta = [0.0632, 0.0, 0.0] } }
[integrator]
method = "rk4"
step = 0.005
[output]
every = 0.1
[effects.hinge_springs]
stiffness = [10.0]
"""


def test_an_energy_budget_that_does_not_close_is_a_warning(tmp_path):
    (tmp_path / "panel_beam_modes.toml").write_bytes(
        (EXAMPLES / "modes" / "panel_beam_modes.toml").read_bytes()
    )
    with pytest.warns(UserWarning, match="the energy budget moved by 5.0"):
        satsim.run(MODES_FILE_SCENE, base_dir=tmp_path)
    # Stepped, at close().
    sim = satsim.Simulation(MODES_FILE_SCENE, base_dir=tmp_path)
    sim.advance(1.0)
    with pytest.warns(UserWarning, match="the energy budget moved by"):
        sim.close()
    # DP5(4) at 1e-8 keeps it: no warning.
    tight = MODES_FILE_SCENE.replace(
        'method = "rk4"\nstep = 0.005', 'method = "dp54"\nrtol = 1e-8\natol = 1e-8'
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        satsim.run(tight, base_dir=tmp_path)
    # A campaign counts the runs, as `satsim campaign` does.
    campaign = """
[campaign]
runs = 2
seed = 1
[[campaign.disperse]]
key = "model.body.0.mass"
uniform = { low = -1.0, high = 1.0 }
"""
    with pytest.warns(UserWarning, match="2 of the 2 finished runs moved their energy budget"):
        satsim.campaign(MODES_FILE_SCENE + campaign, base_dir=tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        satsim.campaign(tight + campaign, base_dir=tmp_path)
