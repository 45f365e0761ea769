"""A satsim scene as a Gymnasium environment (optional extra: ``pip install ./python[gym]``).

::

    import satsim.gym

    env = satsim.gym.Env(
        "examples/scenes/fsw_in_the_loop.toml",
        actions={"wheel_x": (-0.05, 0.05), "wheel_y": (-0.05, 0.05), "wheel_z": (-0.05, 0.05)},
        observation="sensors",                # or "row", or a list of column names
        reward=lambda row, reading, action: -row["omega_x"] ** 2,
    )
    obs, info = env.reset(seed=1)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

One ``step`` is one control period: the action is set as the simulation's inputs (held, zero-
order hold, see :class:`satsim.Simulation`), then the simulation advances ``period`` seconds.

- **Actions**: a ``Box`` over the named inputs (``sim.inputs``: ``torque_<hinge>``,
  ``wheel_<name>``, ``dipole_<torquer>``, ``thrust_<thruster>``), in the order given, with the
  bounds given (finite, ``low < high``; within [0, 1] for a thruster's duty cycle). An action
  outside its bounds is clipped to them (a saturating actuator); one of another length, or
  not numbers, raises :class:`satsim.SatsimError`.
- **Observations**: ``"sensors"`` the sensors' readings (``sim.measure()``'s columns, in the
  order of the trajectory's columns: what flight software sees), ``"row"`` every column of
  the row except ``t`` (the truth), or a list of column names. ``float64``. The space's
  bounds are those each column has: [-1, 1] for a quaternion's components (a star tracker's
  ``w`` in [0, 1]) and a Sun sensor's unit vector, [0, 1] for ``shadow``, [0, 180] for
  ``pointing_error_deg``, >= 0 for thrusts, energies of motion, norms and densities;
  unbounded for the rest.
- **Reward and termination** are the caller's: ``reward(row, reading, action)`` with the row
  and the readings as dicts and the action as a dict of input values (default: 0), and
  ``terminated(row, reading)`` (default: never). The episode is truncated at the scene's
  end, ``t0 + duration`` (``max_time``, a finite time after ``t0``, to change it); ``period``
  (a finite number of seconds > 0) may not exceed the episode. An episode keeps at most
  ``max_rows`` rows of the scene's output grid (default 1 000 000, as
  :class:`satsim.Simulation`): raise it, or the scene's ``output.every``, for longer ones.
- **Order**: ``step`` before the first ``reset`` raises :class:`satsim.SatsimError`.
- **Seeding**: ``reset(seed=...)`` seeds the environment's generator, and each episode's
  sensor noise is drawn from a seed it takes from there (``satsim.Simulation(seed=...)``), so
  the same seed gives the same episode and episodes differ.

``info`` holds ``t`` and the ``events`` that fired during the step (``(t, effect, text)``).

**The runs of a campaign** (a scene with a ``[campaign]`` table, contract sections 8 and 15):
:class:`CampaignEnv` flies run ``k``'s drawn spacecraft in each episode (its dispersed
values, its own sensor noise: what ``satsim.campaign(controller=...)`` flies), and
:func:`make_vector` spreads the runs over ``gymnasium.vector.AsyncVectorEnv``'s worker
processes, one environment each::

    envs = satsim.gym.make_vector("mc.toml", 8, actions={...}, reward=my_reward)
    obs, info = envs.reset(seed=0)        # env i starts with run i, then i + 8, i + 16, ...
"""

from __future__ import annotations

from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

try:
    import gymnasium
    from gymnasium import spaces
except ImportError as e:  # pragma: no cover - exercised only without the extra
    raise ImportError(
        "satsim.gym needs Gymnasium: pip install './python[gym]' (or pip install gymnasium)"
    ) from e

from . import PathLike, SatsimError, Simulation

__all__ = ["CampaignEnv", "Env", "make_vector"]

Reward = Callable[[Dict[str, float], Dict[str, Any], Dict[str, float]], float]
Terminated = Callable[[Dict[str, float], Dict[str, Any]], bool]


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool)


#: Bounds of the row's columns that have them, by name (the rest are unbounded).
_BOUNDS: Dict[str, Tuple[float, float]] = {
    **{f"q_{a}": (-1.0, 1.0) for a in "wxyz"},
    "shadow": (0.0, 1.0),
    "pointing_error_deg": (0.0, 180.0),
    **{c: (0.0, np.inf) for c in ("kinetic_energy", "h_norm", "orbit_radius", "density")},
}


def _column_bounds(column: str, sensor_kinds: Mapping[str, str]) -> Tuple[float, float]:
    """The range a column's values lie in: see the module documentation."""
    if column in _BOUNDS:
        return _BOUNDS[column]
    for name, kind in sensor_kinds.items():
        if kind == "star_tracker" and column == f"{name}_q_w":
            return (0.0, 1.0)
        if kind == "star_tracker" and column in (f"{name}_q_x", f"{name}_q_y", f"{name}_q_z"):
            return (-1.0, 1.0)
        if kind == "sun_sensor" and column in (f"{name}_x", f"{name}_y", f"{name}_z"):
            return (-1.0, 1.0)
    if column.startswith("thrust_"):
        return (0.0, np.inf)
    return (-np.inf, np.inf)


class Env(gymnasium.Env):
    """A satsim scene as a Gymnasium ``Env``; see the module documentation."""

    metadata: Dict[str, Any] = {"render_modes": []}

    def __init__(
        self,
        scene: PathLike,
        actions: Mapping[str, Tuple[float, float]],
        *,
        observation: Union[str, Sequence[str]] = "sensors",
        period: float = 0.1,
        reward: Optional[Reward] = None,
        terminated: Optional[Terminated] = None,
        max_time: Optional[float] = None,
        base_dir: Optional[PathLike] = None,
        max_rows: int = Simulation.MAX_ROWS,
    ) -> None:
        super().__init__()
        self._scene, self._base_dir = scene, base_dir
        self._max_rows = max_rows
        if not (_is_number(period) and np.isfinite(period) and period > 0):
            raise SatsimError(f"period must be a finite number > 0, got {period!r}")
        self._period = float(period)
        self._reward = reward
        self._terminated = terminated
        # A first simulation, to check the names against the scene and size the spaces; the
        # episodes' start at reset().
        sim = self._new_simulation(None)
        self._sim: Optional[Simulation] = None
        if not actions:
            raise SatsimError(f"no actions given; the scene's inputs are {sim.inputs}")
        self._actions: List[str] = list(actions)
        low, high = [], []
        for name, bounds in actions.items():
            if name not in sim.inputs:
                raise SatsimError(f"unknown input `{name}`; the scene's inputs are {sim.inputs}")
            try:
                lo, hi = (float(b) for b in bounds)
            except (TypeError, ValueError):
                raise SatsimError(f"bounds of `{name}` must be (low, high), got {bounds!r}") from None
            if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
                raise SatsimError(f"bounds of `{name}` must be finite with low < high, got {bounds!r}")
            if name.startswith("thrust_") and not (0.0 <= lo and hi <= 1.0):
                raise SatsimError(
                    f"bounds of `{name}` must lie within [0, 1] (a thruster's duty cycle), got {bounds!r}"
                )
            low.append(lo)
            high.append(hi)
        self.action_space = spaces.Box(np.array(low), np.array(high), dtype=np.float64)
        self._observe: List[str] = self._observation_columns(observation, sim)
        kinds = sim.sensor_kinds
        bounds = [_column_bounds(c, kinds) for c in self._observe]
        self.observation_space = spaces.Box(
            np.array([b[0] for b in bounds]), np.array([b[1] for b in bounds]), dtype=np.float64
        )
        t0 = sim.t
        if max_time is None:
            self._max_time = sim.t_end
        elif _is_number(max_time) and np.isfinite(max_time) and max_time > t0:
            self._max_time = float(max_time)
        else:
            raise SatsimError(
                f"max_time must be a finite time (s) after the scene's start t0 = {t0}, got {max_time!r}"
            )
        if self._period > self._max_time - t0:
            raise SatsimError(
                f"period = {self._period} s is longer than an episode (max_time - t0 = "
                f"{self._max_time - t0} s): shorten period or raise max_time"
            )
        sim.close()

    def _new_simulation(self, seed: Optional[int]) -> Simulation:
        return Simulation(self._scene, base_dir=self._base_dir, seed=seed,
                          max_rows=self._max_rows)

    def _observation_columns(self, observation: Union[str, Sequence[str]], sim: Simulation) -> List[str]:
        if isinstance(observation, str):
            if observation == "row":
                return [c for c in sim.columns if c != "t"]
            if observation == "sensors":
                reading = sim.measure()
                names = [c for c in sim.columns if c in reading]
                if not names:
                    raise SatsimError(
                        "observation = 'sensors' but the scene has no [sensors]: add them, or "
                        "use observation = 'row' or a list of columns"
                    )
                return names
            raise SatsimError(
                f"observation must be 'sensors', 'row' or a list of columns, got {observation!r}"
            )
        names = list(observation)
        for c in names:
            if c not in sim.columns:
                raise SatsimError(f"unknown column `{c}` in observation")
        if not names:
            raise SatsimError("observation lists no columns")
        return names

    def _obs(self, row: Dict[str, float], reading: Dict[str, Any]) -> np.ndarray:
        source = {**row, **{k: v for k, v in reading.items() if isinstance(v, float)}}
        return np.array([source[c] for c in self._observe], dtype=np.float64)

    def reset(
        self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[np.ndarray, Dict[str, Any]]:
        super().reset(seed=seed)
        if self._sim is not None:
            self._sim.close()
        episode_seed = int(self.np_random.integers(0, 2**63 - 1))
        self._sim = self._new_simulation(episode_seed)
        row, reading = self._sim.row(), self._sim.measure()
        return self._obs(row, reading), {"t": self._sim.t, "events": []}

    def step(self, action: Any) -> Tuple[np.ndarray, float, bool, bool, Dict[str, Any]]:
        if self._sim is None or self._sim.closed:
            raise SatsimError("step() before reset(): call reset() to start an episode")
        n = len(self._actions)
        try:
            a = np.asarray(action, dtype=np.float64)
        except (TypeError, ValueError):
            raise SatsimError(f"action must be {n} numbers ({', '.join(self._actions)}), got {action!r}") from None
        if a.size != n:
            raise SatsimError(
                f"action must have {n} values ({', '.join(self._actions)}), got shape {a.shape}"
            )
        a = np.clip(a.reshape(-1), self.action_space.low, self.action_space.high)
        values = dict(zip(self._actions, (float(x) for x in a)))
        self._sim.set_inputs(values)
        events = self._sim.advance(self._period)
        row, reading = self._sim.row(), self._sim.measure()
        reward = 0.0 if self._reward is None else float(self._reward(row, reading, values))
        done = False if self._terminated is None else bool(self._terminated(row, reading))
        truncated = self._sim.t >= self._max_time - 1e-9 * max(1.0, abs(self._max_time))
        return self._obs(row, reading), reward, done, truncated, {"t": self._sim.t, "events": events}

    def close(self) -> None:
        if self._sim is not None:
            self._sim.close()
            self._sim = None


class CampaignEnv(Env):
    """:class:`Env` over the runs of a campaign: episode ``e`` of this environment flies run
    ``k = (first + e * stride) % runs`` of the scene's ``[campaign]`` (its drawn values and its
    own sensor seed, as ``satsim.campaign`` draws them), or the run ``reset(options={"run":
    k})`` names. ``info["run"]`` is the episode's run. The spaces are those of run ``first``'s
    scene (every run has the nominal scene's columns and inputs). Same arguments as
    :class:`Env`, plus ``first`` and ``stride``."""

    def __init__(self, scene: PathLike, actions: Mapping[str, Tuple[float, float]], *,
                 first: int = 0, stride: int = 1, base_dir: Optional[PathLike] = None,
                 **kw: Any) -> None:
        import os

        from . import _satsim, _scene_args

        origin, text = _scene_args(scene, base_dir)
        self._campaign = _satsim.NativeCampaign(origin, text)
        if not (isinstance(first, int) and isinstance(stride, int) and first >= 0 and stride >= 1):
            raise SatsimError(f"first must be >= 0 and stride >= 1, got {first!r}, {stride!r}")
        self._runs_dir = os.path.dirname(os.path.abspath(origin)) if text is None else (
            None if base_dir is None else os.fspath(base_dir))
        self._first, self._stride, self._episode = first, stride, 0
        self._run = first % self._campaign.runs
        super().__init__(scene, actions, base_dir=base_dir, **kw)

    def _new_simulation(self, seed: Optional[int]) -> Simulation:
        # The run's scene carries its own sensor seed: `seed` (the episode's) is not used.
        return Simulation(self._campaign.run_text(self._run), base_dir=self._runs_dir,
                          max_rows=self._max_rows)

    def reset(self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
              ) -> Tuple[np.ndarray, Dict[str, Any]]:
        runs = self._campaign.runs
        if options is not None and "run" in options:
            k = options["run"]
            if not (isinstance(k, (int, np.integer)) and 0 <= k < runs):
                raise SatsimError(f"options['run'] must be a run 0 to {runs - 1}, got {k!r}")
            self._run = int(k)
        else:
            self._run = (self._first + self._episode * self._stride) % runs
            self._episode += 1
        obs, info = super().reset(seed=seed, options=options)
        info["run"] = self._run
        return obs, info

    def step(self, action: Any) -> Tuple[np.ndarray, float, bool, bool, Dict[str, Any]]:
        obs, reward, done, truncated, info = super().step(action)
        info["run"] = self._run
        return obs, reward, done, truncated, info


def make_vector(scene: PathLike, num_envs: int, actions: Mapping[str, Tuple[float, float]], *,
                asynchronous: bool = True, **kw: Any) -> Any:
    """``num_envs`` :class:`CampaignEnv` over the campaign's runs (env ``i`` flies runs ``i``,
    ``i + num_envs``, ...), in ``gymnasium.vector.AsyncVectorEnv`` (one worker process each:
    the arguments must pickle, so ``reward`` and ``terminated`` are importable functions) or,
    with ``asynchronous=False``, ``SyncVectorEnv`` (this process)."""
    import functools

    if not (isinstance(num_envs, int) and num_envs >= 1):
        raise SatsimError(f"num_envs must be a whole number >= 1, got {num_envs!r}")
    fns = [functools.partial(CampaignEnv, scene, dict(actions), first=i, stride=num_envs, **kw)
           for i in range(num_envs)]
    vector = gymnasium.vector.AsyncVectorEnv if asynchronous else gymnasium.vector.SyncVectorEnv
    return vector(fns)
