"""`Model.dynamics` against the committed Pinocchio fixtures (an independent implementation),
against `satsim dynamics` (to the last bit), and, when `pin` is installed, against a live
Pinocchio on random trees."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import satsim
from conftest import EXAMPLES, PINOCCHIO

CASES = sorted(p.name[: -len(".expected.json")] for p in PINOCCHIO.glob("*.expected.json"))


def test_every_fixture_is_found():
    # The README lists seven cases; a glob that finds none must not pass silently.
    assert {"satellite", "satellite_rotated", "chain_fixed", "tree_free", "wheel"} <= set(CASES)


def close(got, expected, what):
    """The fixtures' tolerance: |got - expected| <= 1e-10 * max(1, max |expected|)."""
    got, expected = np.asarray(got, float), np.asarray(expected, float)
    assert got.shape == expected.shape, what
    scale = max(1.0, float(np.max(np.abs(expected))) if expected.size else 1.0)
    err = float(np.max(np.abs(got - expected))) if expected.size else 0.0
    assert err <= 1e-10 * scale, f"{what}: max error {err:.3e} (scale {scale:.3e})"


@pytest.mark.parametrize("case", CASES)
def test_dynamics_matches_pinocchio_fixture(case):
    m = satsim.Model.from_file(PINOCCHIO / f"{case}.model.toml")
    d = m.dynamics(PINOCCHIO / f"{case}.state.json")
    want = json.loads((PINOCCHIO / f"{case}.expected.json").read_text())
    assert isinstance(d["dof"], int) and d["dof"] == want["dof"] == m.dof
    assert d["mass_matrix"].dtype == np.float64 and d["mass_matrix"].shape == (m.dof, m.dof)
    assert d["bias"].shape == d["acceleration"].shape == (m.dof,)
    assert isinstance(d["kinetic_energy"], float)
    close(d["mass_matrix"], want["mass_matrix"], "mass_matrix")
    close(d["bias"], want["bias"], "bias")
    close(d["acceleration"], want["acceleration"], "acceleration")
    close(d["kinetic_energy"], want["kinetic_energy"], "kinetic_energy")


def bits(x):
    return np.asarray(x, dtype=np.float64).view(np.uint64)


@pytest.mark.parametrize("case", CASES)
def test_dynamics_equals_the_command_line_to_the_last_bit(cli, case):
    model, state = PINOCCHIO / f"{case}.model.toml", PINOCCHIO / f"{case}.state.json"
    out = subprocess.run(
        [cli, "dynamics", "--model", model, "--state", state],
        check=True, capture_output=True, text=True,
    ).stdout
    want = json.loads(out)  # the CLI prints shortest round-trip numbers: exact
    d = satsim.Model.from_file(model).dynamics(state)
    assert d["dof"] == want["dof"]
    for key in ("mass_matrix", "bias", "acceleration", "kinetic_energy"):
        np.testing.assert_array_equal(bits(d[key]), bits(want[key]), err_msg=key)


@pytest.mark.parametrize("middle", [1.5706963267984133, -1.5707000000070335])
def test_near_a_gimbal_lock_dynamics_gives_the_command_lines_bits(cli, tmp_path, middle):
    # The 3-DOF hinge's middle angle 1e-4 rad from +-90 degrees, where the accelerations
    # magnify the last bit of an angle. Both angles are numbers a JSON reader without exact
    # float parsing reads 1 ulp off (`satsim` built alone once did, unlike the module).
    model = EXAMPLES / "satellite.toml"

    def state(mid):
        return {
            "base": {"attitude": [1.0, 0.0, 0.0, 0.0], "angular_velocity": [0.001, -0.002, 0.0015]},
            "hinges": {
                "angle": [0.3, mid, 0.1, 1.2, -1.0],
                "rate": [0.01, 0.02, -0.01, 0.05, -0.04],
                "torque": [0.0, 0.0, 0.0, -0.5, 0.4],
            },
        }

    path = tmp_path / "lock.json"
    path.write_text(json.dumps(state(middle)))
    out = subprocess.run(
        [cli, "dynamics", "--model", model, "--state", path],
        check=True, capture_output=True, text=True,
    ).stdout
    want = json.loads(out)
    m = satsim.Model.from_file(model)
    for d in (m.dynamics(path), m.dynamics(state(middle))):
        for key in ("mass_matrix", "bias", "acceleration", "kinetic_energy"):
            np.testing.assert_array_equal(bits(d[key]), bits(want[key]), err_msg=key)
    # The check can tell: an angle 1 ulp away gives other accelerations.
    nudged = m.dynamics(state(float(np.nextafter(middle, 0.0))))
    assert not np.array_equal(bits(nudged["acceleration"]), bits(want["acceleration"]))


def test_state_as_path_text_dict_and_numpy_give_the_same_bits():
    m = satsim.Model.from_file(PINOCCHIO / "satellite_rotated.model.toml")
    path = PINOCCHIO / "satellite_rotated.state.json"
    text = path.read_text()
    doc = json.loads(text)
    as_numpy = {
        "base": {k: np.array(v) for k, v in doc["base"].items()},
        "hinges": {k: np.array(v) for k, v in doc["hinges"].items()},
    }
    results = [m.dynamics(path), m.dynamics(str(path)), m.dynamics(text), m.dynamics(doc),
               m.dynamics(as_numpy)]
    for r in results[1:]:
        for key in ("mass_matrix", "bias", "acceleration", "kinetic_energy"):
            np.testing.assert_array_equal(bits(r[key]), bits(results[0][key]), err_msg=key)


def test_from_toml_equals_from_file():
    path = EXAMPLES / "satellite.toml"
    a = satsim.Model.from_file(path)
    b = satsim.Model.from_toml(path.read_text())
    assert a.hinge_names == b.hinge_names == ["h1", "h2", "h3", "h4", "h5"]
    assert a.base == "free" and a.dof == 11
    state = EXAMPLES / "state.json"
    np.testing.assert_array_equal(a.dynamics(state)["acceleration"],
                                  b.dynamics(state)["acceleration"])


def test_equation_of_motion_holds():
    # M a + b = tau (zero on the base, the torques on the hinges), and T = v'Mv/2.
    m = satsim.Model.from_file(PINOCCHIO / "tree_free_big.model.toml")
    doc = json.loads((PINOCCHIO / "tree_free_big.state.json").read_text())
    d = m.dynamics(doc)
    tau = np.concatenate([np.zeros(6), doc["hinges"]["torque"]])
    v = np.concatenate([doc["base"]["angular_velocity"], doc["base"]["velocity"],
                        doc["hinges"]["rate"]])
    M = d["mass_matrix"]
    np.testing.assert_allclose(M, M.T, rtol=0, atol=1e-12 * np.abs(M).max())
    np.testing.assert_allclose(M @ d["acceleration"] + d["bias"], tau,
                               rtol=0, atol=1e-9 * np.abs(M).max())
    assert d["kinetic_energy"] == pytest.approx(0.5 * v @ M @ v, rel=1e-12)


# ---------------------------------------------------------------------------------------
# Live Pinocchio (optional: `pip install pin`), random trees. CI (`.ci/python.sh`) installs
# it and sets SATSIM_REQUIRE_PINOCCHIO=1: there these tests fail rather than skip.

REQUIRE_PINOCCHIO = os.environ.get("SATSIM_REQUIRE_PINOCCHIO") == "1"


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_trees_against_live_pinocchio(tmp_path, seed):
    if REQUIRE_PINOCCHIO:
        import pinocchio  # noqa: F401  (an ImportError fails the test)
        assert sys.version_info >= (3, 11), "the fixture generator needs tomllib (Python >= 3.11)"
    pytest.importorskip("pinocchio", reason="live Pinocchio check needs `pip install pin`")
    if sys.version_info < (3, 11):
        pytest.skip("the fixture generator needs tomllib (Python >= 3.11)")
    sys.path.insert(0, str(PINOCCHIO))
    try:
        import make_fixtures as mf
    finally:
        sys.path.pop(0)
    rng = np.random.default_rng(1000 + seed)
    n = 6 + 4 * seed
    parents = mf.random_tree(rng, n)
    bodies = [mf.rand_body(rng, "base", mass_range=(100.0, 300.0), size=1.0)]
    bodies += [mf.rand_body(rng, f"body{i}") for i in range(1, n)]
    hinges = [mf.rand_hinge(rng, f"hinge{i}", bodies[parents[i]]["name"], bodies[i]["name"])
              for i in range(1, n)]
    hinges = [hinges[i] for i in rng.permutation(len(hinges))]
    model_path, state_path = tmp_path / "m.toml", tmp_path / "s.json"
    mf.write_model(str(model_path), "free", bodies, hinges)
    mf.write_state(str(state_path), "free", mf.rand_state(rng, "free", len(hinges)))
    ref_model = mf.read_model(str(model_path))
    ref = mf.pinocchio_dynamics(ref_model, mf.read_state(str(state_path), ref_model))
    d = satsim.Model.from_file(model_path).dynamics(state_path)
    close(d["mass_matrix"], ref["M"], "mass_matrix")
    close(d["bias"], ref["bias"], "bias")
    close(d["acceleration"], ref["acc"], "acceleration")
    close(d["kinetic_energy"], ref["ke"], "kinetic_energy")
