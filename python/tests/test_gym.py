"""satsim.gym: a scene as a Gymnasium Env (the optional `gym` extra)."""

from __future__ import annotations

import os

import numpy as np
import pytest

import satsim
from conftest import SCENES

# CI installs the `gym` extra and sets SATSIM_REQUIRE_GYM=1: there these tests fail rather
# than skip when Gymnasium is missing.
if os.environ.get("SATSIM_REQUIRE_GYM") == "1":
    import gymnasium  # noqa: F401
else:
    pytest.importorskip("gymnasium")

import satsim.gym  # noqa: E402
from gymnasium.utils.env_checker import check_env  # noqa: E402

DEPLOY = SCENES / "deploy.toml"
KD_LINE = "kd = 150.0               # N m s/rad"
WHEELS = {f"wheel_{a}": (-0.05, 0.05) for a in "xyz"}


def deploy_text(duration: float, extra: str = "") -> str:
    text = DEPLOY.read_text()
    assert "duration = 300.0" in text and KD_LINE in text
    text = text.replace("duration = 300.0", f"duration = {duration}", 1)
    return text.replace(KD_LINE, "kd = 150.0\nenabled = false\n", 1) + extra


SENSORS = """
[sensors]
seed = 3
[[sensors.gyro]]
name = "gyro"
body = "bus"
period = 0.1
noise_density = 1e-4
bias_walk = 1e-6
[[sensors.star_tracker]]
name = "st"
body = "bus"
period = 0.1
noise_arcsec = [5.0, 5.0, 40.0]
"""


def env(observation="row", **kw) -> "satsim.gym.Env":
    extra = SENSORS if observation == "sensors" else ""
    return satsim.gym.Env(
        deploy_text(2.0, extra), WHEELS, observation=observation, base_dir=SCENES, **kw
    )


@pytest.mark.parametrize("observation", ["row", "sensors"])
def test_the_env_passes_gymnasiums_checker(observation):
    e = env(observation)
    check_env(e, skip_render_check=True)
    e.close()


def test_a_step_is_a_control_period_with_the_action_held():
    """Three steps of a held action are the same as the simulation with the inputs set."""
    e = env(reward=lambda row, reading, action: -row["omega_x"] ** 2)
    obs, info = e.reset(seed=0)
    a = np.array([0.01, -0.02, 0.03])
    for _ in range(3):
        obs, reward, terminated, truncated, info = e.step(a)
    assert info["t"] == pytest.approx(0.3, abs=1e-12)
    with satsim.Simulation(deploy_text(2.0), base_dir=SCENES) as sim:
        sim.set_inputs({"wheel_x": 0.01, "wheel_y": -0.02, "wheel_z": 0.03})
        for _ in range(3):
            sim.advance(0.1)
        row = sim.row()
    columns = [c for c in sim.columns if c != "t"]
    assert np.array_equal(obs, np.array([row[c] for c in columns]))
    assert reward == -row["omega_x"] ** 2
    assert not terminated and not truncated


def test_actions_are_clipped_to_their_bounds():
    e = env()
    e.reset(seed=0)
    e.step(np.array([1.0, -1.0, 0.0]))
    clipped = e.step(np.array([1.0, -1.0, 0.0]))[0]
    e2 = env()
    e2.reset(seed=0)
    e2.step(np.array([0.05, -0.05, 0.0]))
    held = e2.step(np.array([0.05, -0.05, 0.0]))[0]
    assert np.array_equal(clipped, held)


def test_the_episode_is_truncated_at_the_scenes_duration():
    e = env()
    e.reset(seed=0)
    truncated, n = False, 0
    while not truncated:
        truncated = e.step(np.zeros(3))[3]
        n += 1
    assert n == 20


def test_sensor_noise_follows_the_reset_seed():
    e = env("sensors")
    first = e.reset(seed=7)[0]
    again = e.reset(seed=7)[0]
    other = e.reset(seed=8)[0]
    assert np.array_equal(first, again)
    assert not np.array_equal(first, other)


def test_bad_arguments_name_what_is_wrong():
    with pytest.raises(satsim.SatsimError, match="unknown input `wheel_q`"):
        satsim.gym.Env(deploy_text(2.0), {"wheel_q": (-1, 1)}, observation="row", base_dir=SCENES)
    with pytest.raises(satsim.SatsimError, match="low < high"):
        satsim.gym.Env(deploy_text(2.0), {"wheel_x": (1, -1)}, observation="row", base_dir=SCENES)
    with pytest.raises(satsim.SatsimError, match="no \\[sensors\\]"):
        satsim.gym.Env(deploy_text(2.0), WHEELS, observation="sensors", base_dir=SCENES)
    with pytest.raises(satsim.SatsimError, match="unknown column `nope`"):
        satsim.gym.Env(deploy_text(2.0), WHEELS, observation=["nope"], base_dir=SCENES)
    with pytest.raises(satsim.SatsimError, match="period"):
        satsim.gym.Env(deploy_text(2.0), WHEELS, observation="row", period=0.0, base_dir=SCENES)


def test_bad_max_time_thrust_bounds_and_period_are_refused_at_construction():
    for bad in (float("nan"), float("inf"), -1.0, 0.0, "3", True):
        with pytest.raises(satsim.SatsimError, match="max_time must be a finite time"):
            env(max_time=bad)
    with pytest.raises(satsim.SatsimError, match=r"period = 1000000000(\.0)? s is longer than an episode"):
        env(period=1e9)
    with pytest.raises(satsim.SatsimError, match=r"period = 0.5 s is longer than an episode \(max_time - t0 = 0.25 s\)"):
        env(period=0.5, max_time=0.25)
    text = THRUSTERS
    for bounds in ((-0.5, 1.0), (0.0, 2.0)):
        with pytest.raises(satsim.SatsimError, match=r"bounds of `thrust_roll` must lie within \[0, 1\]"):
            satsim.gym.Env(text, {"thrust_roll": bounds}, observation="row")
    e = satsim.gym.Env(text, {"thrust_roll": (0.0, 1.0)}, observation="row", max_time=0.35)
    e.reset(seed=0)
    truncated = [e.step(np.array([1.0]))[3] for _ in range(4)]
    assert truncated == [False, False, False, True]


def test_step_before_reset_and_a_wrong_action_raise_naming_them():
    e = env()
    with pytest.raises(satsim.SatsimError, match=r"step\(\) before reset\(\)"):
        e.step(np.zeros(3))
    e.reset(seed=0)
    with pytest.raises(satsim.SatsimError, match=r"action must have 3 values \(wheel_x, wheel_y, wheel_z\), got shape \(2,\)"):
        e.step(np.zeros(2))
    with pytest.raises(satsim.SatsimError, match="action must be 3 numbers"):
        e.step(["a", "b", "c"])
    e.step([0.0, 0.0, 0.0])


def test_the_observation_space_has_each_columns_bounds():
    e = env("row")
    space = e.observation_space
    names = e._observe
    for c in ("q_w", "q_x", "q_y", "q_z"):
        i = names.index(c)
        assert (space.low[i], space.high[i]) == (-1.0, 1.0)
    i = names.index("omega_x")
    assert (space.low[i], space.high[i]) == (-np.inf, np.inf)
    i = names.index("kinetic_energy")
    assert (space.low[i], space.high[i]) == (0.0, np.inf)
    s = env("sensors")
    names, space = s._observe, s.observation_space
    assert (space.low[names.index("st_q_w")], space.high[names.index("st_q_w")]) == (0.0, 1.0)
    assert (space.low[names.index("st_q_z")], space.high[names.index("st_q_z")]) == (-1.0, 1.0)
    assert (space.low[names.index("gyro_x")], space.high[names.index("gyro_x")]) == (-np.inf, np.inf)
    obs = s.reset(seed=1)[0]
    for _ in range(5):
        assert space.contains(obs)
        obs = s.step(np.zeros(3))[0]
    t = satsim.gym.Env(THRUSTERS, {"thrust_roll": (0.0, 1.0)}, observation=["thrust_roll", "h_x"])
    assert list(t.observation_space.low) == [0.0, -np.inf]


THRUSTERS = """
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
"""


CAMPAIGN = """
[campaign]
runs = 4
seed = 5
[[campaign.disperse]]
key = "initial.base.angular_velocity"
normal = { sigma = 0.002 }
"""


@pytest.mark.parametrize("asynchronous", [False, True])
def test_the_vector_env_flies_the_campaigns_runs(asynchronous):
    """Env i of 2 flies runs i, i + 2: with zero actions each episode ends where the
    campaign's run with a controller that sets nothing ends (its final row, bit for bit)."""
    text = deploy_text(1.0, SENSORS + CAMPAIGN)
    envs = satsim.gym.make_vector(text, 2, WHEELS, observation="row", base_dir=SCENES,
                                  asynchronous=asynchronous)
    try:
        finals = {}
        obs, info = envs.reset(seed=0)
        assert list(info["run"]) == [0, 1]
        for episode in range(2):
            runs = [int(k) for k in info["run"]]
            done = np.zeros(2, dtype=bool)
            while not done.all():
                obs, _, term, trunc, info = envs.step(np.zeros((2, 3)))
                for i in np.flatnonzero(trunc | term):
                    if not done[i]:
                        finals[runs[i]] = obs[i].copy() if "final_obs" not in info else \
                            info["final_obs"][i]
                done |= trunc | term
            if episode == 0:
                obs, info = envs.reset()
                assert list(info["run"]) == [2, 3]
    finally:
        envs.close()
    assert sorted(finals) == [0, 1, 2, 3]

    class Nothing:
        def step(self, t, meas, row):
            return {}

    res = satsim.campaign(text, base_dir=SCENES, controller=lambda run: Nothing(), period=0.1)
    sim = satsim.Simulation(deploy_text(1.0, SENSORS), base_dir=SCENES)
    columns = [c for c in sim.columns if c != "t"]
    for k, final in finals.items():
        expected = np.array([res[f"final_{c}"][k] for c in columns])
        assert np.array_equal(np.asarray(final).view(np.uint64), expected.view(np.uint64)), k


def test_an_episode_longer_than_max_rows_is_refused_when_it_would_pass_it():
    """`max_rows` reaches the episode's simulation: a step that would keep more rows raises
    before it integrates; a larger bound lets the same episode run."""
    text = deploy_text(2.0, SENSORS)
    env = satsim.gym.Env(text, WHEELS, base_dir=SCENES, max_rows=3)
    env.reset(seed=0)
    with pytest.raises(satsim.SatsimError, match="max_rows"):
        for _ in range(100):
            env.step(np.zeros(3))
    env = satsim.gym.Env(text, WHEELS, base_dir=SCENES, max_rows=1000)
    env.reset(seed=0)
    for _ in range(20):
        env.step(np.zeros(3))
