"""satsim: attitude dynamics of hinged spacecraft, from Python.

The same engine and the same code as the ``satsim`` command line (contract section 10), so
every number equals the command line's to the last bit::

    import satsim
    m = satsim.Model.from_file("model.toml")      # bad input raises satsim.SatsimError
    d = m.dynamics("state.json")                  # or JSON text, or a dict
    d["mass_matrix"], d["bias"], d["acceleration"], d["kinetic_energy"], d["dof"]
    r = satsim.run("scene.toml")                  # nothing written to disk
    r.columns, r.data, r["angle_h4"], r.to_pandas()
    c = satsim.campaign("campaign.toml")          # runs.csv in memory: c.columns, c.data, c.status
    r = satsim.read_trajectory("out/deploy/trajectory.csv")   # a run's CSV, read back
    satsim.modes("scene.toml"), satsim.linearize("scene.toml")   # dicts, numpy arrays
    with satsim.Simulation("scene.toml") as sim:  # stepped from your code (section 13)
        sim.set_inputs({"wheel_x": 0.01}); events = sim.advance(0.1); sim.row()

Conventions (the contract's): SI units; quaternions Hamilton ``[w, x, y, z]``; the
generalised velocity of a free base is ``[angular_velocity (3), velocity (3), hinge rates]``
in root-body axes (Featherstone's angular-then-linear order), of a fixed base ``[hinge
rates]``; hinge arrays follow the model file's ``[[hinge]]`` order; ``mass_matrix @
acceleration + bias == tau`` with ``tau`` zero on the base and the hinge torques on the hinges.

The module releases the GIL while it reads files and computes: several Python threads can
run scenes at once.
"""

from __future__ import annotations

import json
import math
import os
import warnings
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Mapping, Optional, Tuple, Union

import numpy as np

from . import _satsim
from ._satsim import SatsimError

__all__ = [
    "CampaignResult",
    "Model",
    "Run",
    "SatsimError",
    "Simulation",
    "Trajectory",
    "campaign",
    "linearize",
    "modes",
    "read_trajectory",
    "run",
]

__version__: str = _satsim.__version__

#: A file path: ``str`` or ``os.PathLike``.
PathLike = Union[str, "os.PathLike[str]"]

#: The names that label inputs given as text in error messages.
MODEL_TEXT = "<model text>"
STATE_TEXT = "<state text>"
STATE_DICT = "<state dict>"
SCENE_TEXT = "<scene text>"


def _json_default(x: Any) -> Any:
    """Lets ``json.dumps`` write numpy arrays and scalars (exactly: ``repr`` round-trips)."""
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"{type(x).__name__} is not a number or an array of numbers")


def _is_scene_text(scene: str) -> bool:
    """A string is a scene's text when it has a line break, or names no file and has a ``=``."""
    return "\n" in scene or ("=" in scene and not os.path.isfile(scene))


class Model:
    """A hinged tree (contract section 1), read and checked. Immutable. Its bodies may be
    flexible (``[body.flexible]``, contract section 14).

    Build it with :meth:`from_file` or :meth:`from_toml`; bad input raises
    :class:`SatsimError` with the command line's message (file, line, key).
    """

    __slots__ = ("_native",)

    def __init__(self, native: _satsim.NativeModel) -> None:
        """Internal: use :meth:`from_file` or :meth:`from_toml`."""
        if not isinstance(native, _satsim.NativeModel):
            raise TypeError("use satsim.Model.from_file(path) or satsim.Model.from_toml(text)")
        self._native = native

    @classmethod
    def from_file(cls, path: PathLike) -> "Model":
        """Reads the model file (TOML, contract section 1) at ``path``."""
        return cls(_satsim.NativeModel.from_file(os.fspath(path)))

    @classmethod
    def from_toml(cls, text: str, name: str = MODEL_TEXT, *,
                  base_dir: Optional[PathLike] = None) -> "Model":
        """Parses a model file's text; ``name`` stands for the file in error messages.

        ``base_dir``: the folder that a flexible body's ``modes_file`` given as a relative
        path is read from, as :meth:`from_file` reads it from the file's folder: the text
        stands for a file named ``name`` in ``base_dir`` (so messages and :attr:`origin` name
        ``<base_dir>/<model text>``). Without it, relative paths are read from ``name``'s
        folder: the current directory for the default name."""
        if not isinstance(text, str):
            raise TypeError(f"the model text must be a str, got {type(text).__name__}")
        origin = name
        if base_dir is not None:
            # The reader resolves `modes_file` from its origin's folder.
            origin = os.path.join(os.fspath(base_dir), os.path.basename(name) or MODEL_TEXT)
        return cls(_satsim.NativeModel.from_toml(text, origin))

    @property
    def dof(self) -> int:
        """Degrees of freedom: 6 + hinges for a free base, the hinges for a fixed one, plus
        the flexible bodies' modes."""
        return self._native.dof

    @property
    def base(self) -> str:
        """``"free"`` or ``"fixed"``."""
        return self._native.base

    @property
    def body_names(self) -> List[str]:
        """Body names, the root first (parents before children)."""
        return self._native.body_names

    @property
    def hinge_names(self) -> List[str]:
        """Hinge names in the model file's order (the order of every hinge array)."""
        return self._native.hinge_names

    @property
    def total_mass(self) -> float:
        """Total mass (kg)."""
        return self._native.total_mass

    @property
    def origin(self) -> str:
        """The model file's path, or ``<model text>`` (in ``base_dir`` when :meth:`from_toml`
        was given one)."""
        return os.fspath(self._native.origin)

    @property
    def flexible(self) -> Dict[str, int]:
        """The flexible bodies (contract section 14) and their numbers of modes, in the
        model's order (parents before children); ``{}`` for a rigid model. The elastic
        coordinates follow the hinge rates in this order, each body's mode 1 first."""
        return dict(self._native.flexible)

    @property
    def modal_frequencies(self) -> Dict[str, np.ndarray]:
        """The flexible bodies' clamped modal frequencies (Hz), mode 1 first: each body's
        own modes with its hinge and the rest of the tree held still (``ωₖ / 2π``)."""
        return {
            body: np.asarray(hz, dtype=np.float64)
            for body, hz in self._native.modal_frequencies
        }

    def _state_call(self, state: Union[PathLike, str, Mapping[str, Any]], what: str) -> Any:
        """Calls the native ``<what>_file`` or ``<what>_json`` with ``state``."""
        if isinstance(state, Mapping):
            text = json.dumps(state, default=_json_default)
            return getattr(self._native, f"{what}_json")(text, STATE_DICT)
        if isinstance(state, str) and state.lstrip().startswith("{"):
            return getattr(self._native, f"{what}_json")(state, STATE_TEXT)
        if isinstance(state, (str, os.PathLike)):
            return getattr(self._native, f"{what}_file")(os.fspath(state))
        raise TypeError(
            "state must be a path, a state file's JSON text or a dict, "
            f"got {type(state).__name__}"
        )

    def dynamics(self, state: Union[PathLike, str, Mapping[str, Any]]) -> Dict[str, Any]:
        """The dynamics of one state, as ``satsim dynamics`` (contract section 3).

        ``state`` is a state file's path, a state file's JSON text (a string starting with
        ``{``) or a dict with the state file's keys (lists or numpy arrays), for example
        ``{"hinges": {"angle": [...], "rate": [...]}}``. With flexible bodies it may give
        their elastic state: ``{"flexible": {"panel1": {"eta": [...], "etadot": [...]}}}``
        (default zeros).

        Returns a dict: ``dof`` (int), ``mass_matrix`` (``dof x dof`` float64 array),
        ``bias`` and ``acceleration`` (float64 arrays of length ``dof``) and
        ``kinetic_energy`` (float, J), with ``mass_matrix @ acceleration + bias == tau``.
        With flexible bodies the modes follow the hinge rates (see :attr:`flexible`), the
        bias includes the modal stiffness and damping forces, and ``tau`` is zero on them.
        """
        dof, mass_matrix, bias, acceleration, kinetic_energy = self._state_call(
            state, "dynamics"
        )
        return {
            "dof": dof,
            "mass_matrix": mass_matrix,
            "bias": bias,
            "acceleration": acceleration,
            "kinetic_energy": kinetic_energy,
        }

    def modes(self, state: Union[PathLike, str, Mapping[str, Any]]) -> Dict[str, Any]:
        """The coupled undamped structural modes at the configuration of ``state`` (as
        :meth:`dynamics` takes it): the solutions of ``K x = ω² M(q) x``, ``M`` the mass
        matrix of :meth:`dynamics` and ``K`` the modal stiffness (``ωₖ²`` on each elastic
        coordinate, zero on the rigid ones: hinge springs, geometric stiffening, damping and
        any control left out). The velocities in ``state`` are not used.

        Returns a dict: ``omega`` (rad/s, ascending, one per elastic coordinate: the rigid
        coordinates' zero frequencies left out), ``frequencies_hz`` (``omega / 2π``) and
        ``shapes`` (``dof x len(omega)``, one column per mode, in the generalised velocity's
        coordinates, mass-normalised ``xᵀ M x = 1``, the largest elastic entry positive).
        Empty for a rigid model.
        """
        omega, shapes = self._state_call(state, "modes")
        return {
            "omega": omega,
            "frequencies_hz": omega / (2.0 * np.pi),
            "shapes": shapes,
        }

    def __repr__(self) -> str:
        return (
            f"satsim.Model({self.origin!r}: {self.base} base, {len(self.body_names)} bodies, "
            f"{len(self.hinge_names)} hinges, {self.dof} dof)"
        )


class Trajectory:
    """A run's output: the trajectory CSV's header and values (contract section 7).

    ``columns`` is the header (a list of str), ``data`` the values (a 2-D float64 array, one
    row per output time); ``r["angle_h4"]`` is one column as a 1-D array (a view of ``data``).
    """

    __slots__ = ("columns", "data", "_index")

    def __init__(self, columns: List[str], data: np.ndarray) -> None:
        data = np.asarray(data, dtype=np.float64)
        if data.ndim != 2 or data.shape[1] != len(columns):
            raise ValueError(
                f"data of shape {data.shape} does not fit {len(columns)} columns"
            )
        self.columns: List[str] = list(columns)
        self.data: np.ndarray = data
        self._index = {c: i for i, c in enumerate(self.columns)}

    def __getitem__(self, column: str) -> np.ndarray:
        """One column, by name, as a 1-D array."""
        try:
            return self.data[:, self._index[column]]
        except KeyError:
            raise KeyError(
                f"no column {column!r}; the columns are {', '.join(self.columns)}"
            ) from None

    def __contains__(self, column: object) -> bool:
        return column in self._index

    def __len__(self) -> int:
        """The number of rows."""
        return int(self.data.shape[0])

    def __iter__(self) -> Iterator[str]:
        """The column names (as a dict's keys)."""
        return iter(self.columns)

    def keys(self) -> List[str]:
        """The column names."""
        return list(self.columns)

    @property
    def t(self) -> np.ndarray:
        """The output times (s), the ``t`` column."""
        return self["t"]

    def to_pandas(self) -> Any:
        """The trajectory as a ``pandas.DataFrame`` (needs pandas)."""
        try:
            import pandas as pd
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("to_pandas() needs pandas: pip install pandas") from e
        return pd.DataFrame(self.data, columns=self.columns)

    def __repr__(self) -> str:
        span = ""
        if len(self) and "t" in self:
            span = f", t = {self.t[0]} .. {self.t[-1]} s"
        return f"satsim.Trajectory({len(self)} rows x {len(self.columns)} columns{span})"


def read_trajectory(path: PathLike) -> Trajectory:
    """Reads a ``trajectory.csv`` that ``satsim run`` wrote (contract section 7).

    A last line without its line end (a run killed while writing it) is left out with a
    :class:`UserWarning`: the result holds every whole row. Anything else that is not a
    header and rows of numbers (an empty file, a row of the wrong length, a field that is not
    a number) raises :class:`SatsimError` naming the file and line. An empty field (a value
    a failed run did not reach) reads as NaN.
    """
    name = os.fspath(path)
    with open(name, "r", encoding="utf-8", newline="") as f:
        text = f.read()
    lines = text.split("\n")
    # The text after the last line end is "" for a whole file, else a cut-off row.
    cut = lines.pop()
    if cut.strip():
        warnings.warn(
            f"{name}:{len(lines) + 1}: the last line has no line end (the run was stopped "
            "while writing it?): left out; read the rows before it",
            UserWarning,
            stacklevel=2,
        )
    lines = [line.rstrip("\r") for line in lines]
    if not lines or not lines[0].strip():
        raise SatsimError(f"{name}: the file is empty")
    columns = [c.strip() for c in lines[0].split(",")]
    rows = []
    for n, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        fields = line.split(",")
        if len(fields) != len(columns):
            raise SatsimError(
                f"{name}:{n}: {len(fields)} fields, the header has {len(columns)}"
            )
        row = []
        for c, field in zip(columns, fields):
            field = field.strip()
            try:
                row.append(float(field) if field else math.nan)
            except ValueError:
                raise SatsimError(
                    f"{name}:{n}: `{field}` in column `{c}` is not a number"
                ) from None
        rows.append(row)
    data = np.array(rows, dtype=np.float64).reshape(len(rows), len(columns))
    return Trajectory(columns, data)


def _run_partial(e: SatsimError) -> SatsimError:
    """Turns the native ``(columns, data)`` of a failed run into a :class:`Trajectory`."""
    partial = getattr(e, "partial", None)
    if isinstance(partial, tuple):
        e.partial = Trajectory(*partial)  # type: ignore[attr-defined]
    return e


def run(
    scene: PathLike,
    out: Optional[PathLike] = None,
    *,
    base_dir: Optional[PathLike] = None,
) -> Trajectory:
    """Runs a scene (contract section 7) exactly as ``satsim run`` does.

    ``scene`` is a scene file's path or the scene's TOML text (a string with a line break, or
    with a ``=`` and naming no file). The relative paths in a scene's text (``model = ...``)
    are taken from ``base_dir`` (default: the current directory).

    ``out=None`` writes nothing; ``out=DIR`` also writes ``DIR/trajectory.csv`` (and the
    plots the scene asks for), as the command line does.

    Bad input raises :class:`SatsimError` with the command line's message. A run that fails
    part-way raises :class:`SatsimError` too; its ``partial`` attribute is the
    :class:`Trajectory` up to the failure. Ctrl-C stops a run (``KeyboardInterrupt``).

    What ``satsim run`` warns of after a run (the scene reader's warnings; a flexible beam
    bent past a tenth of its length, beyond what its modal model holds) comes as a
    :class:`UserWarning` each.
    """
    out_path = None if out is None else os.fspath(out)
    origin, text = _scene_args(scene, base_dir)
    try:
        if text is not None:
            columns, data, said = _satsim.run_text(text, origin, out_path)
        else:
            columns, data, said = _satsim.run_file(origin, out_path)
    except SatsimError as e:
        raise _run_partial(e) from None
    for w in said:
        warnings.warn(w, UserWarning, stacklevel=2)
    return Trajectory(columns, data)


def _scene_args(scene: PathLike, base_dir: Optional[PathLike]) -> "tuple[str, Optional[str]]":
    """``(origin, text)`` for the native functions: a path and no text, or the text and the
    name that stands for it (in ``base_dir``, which anchors its relative paths)."""
    if isinstance(scene, str) and _is_scene_text(scene):
        origin = SCENE_TEXT if base_dir is None else os.path.join(os.fspath(base_dir), SCENE_TEXT)
        return origin, scene
    if isinstance(scene, (str, os.PathLike)):
        return os.fspath(scene), None
    raise TypeError(f"scene must be a path or a scene's text, got {type(scene).__name__}")


class CampaignResult:
    """A campaign's ``runs.csv`` (contract section 8), in memory: one row per run, sorted by
    the run number ``run``.

    ``columns`` is ``runs.csv``'s header; ``data`` (2-D float64) holds its numbers bit for bit,
    with the two text columns encoded: ``status`` is 1.0 (``ok``) or 0.0 (``failed``) and
    ``message`` is NaN. A failed run's statistics are NaN. The texts are in ``status`` and
    ``messages`` (lists of str); ``c["status"]`` and ``c["message"]`` return them as arrays of
    str, any other ``c["final_angle_h4"]`` a column of ``data``.
    """

    __slots__ = ("columns", "data", "status", "messages", "out", "_index")

    def __init__(
        self, columns: List[str], data: np.ndarray, status: List[str], messages: List[str]
    ) -> None:
        data = np.asarray(data, dtype=np.float64)
        if data.ndim != 2 or data.shape != (len(status), len(columns)) or len(messages) != len(status):
            raise ValueError("the columns, data, status and messages do not fit together")
        self.columns: List[str] = list(columns)
        self.data: np.ndarray = data
        self.status: List[str] = list(status)
        self.messages: List[str] = list(messages)
        #: The campaign folder written (``out=``), or ``None`` for a campaign in memory.
        self.out: Optional[str] = None
        self._index = {c: i for i, c in enumerate(self.columns)}

    @property
    def table(self) -> "CampaignResult":
        """``runs.csv`` as a table: this object itself (contract section 15's ``res.table``)."""
        return self

    def __getitem__(self, column: str) -> np.ndarray:
        """One column, by name: an array of str for ``status`` and ``message``, a 1-D float
        array (a view of ``data``) for any other."""
        if column == "status":
            return np.array(self.status, dtype=str)
        if column == "message":
            return np.array(self.messages, dtype=str)
        try:
            return self.data[:, self._index[column]]
        except KeyError:
            raise KeyError(
                f"no column {column!r}; the columns are {', '.join(self.columns)}"
            ) from None

    def __contains__(self, column: object) -> bool:
        return column in self._index

    def __len__(self) -> int:
        """The number of runs."""
        return len(self.status)

    def __iter__(self) -> Iterator[str]:
        """The column names."""
        return iter(self.columns)

    def keys(self) -> List[str]:
        """The column names."""
        return list(self.columns)

    @property
    def ok(self) -> np.ndarray:
        """A boolean mask of the runs that finished."""
        return np.array([s == "ok" for s in self.status], dtype=bool)

    def to_pandas(self) -> Any:
        """The table as a ``pandas.DataFrame``, as ``runs.csv`` reads (``run`` as integers,
        ``status`` and ``message`` as text); needs pandas."""
        try:
            import pandas as pd
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("to_pandas() needs pandas: pip install pandas") from e
        df = pd.DataFrame(self.data, columns=self.columns)
        df["run"] = df["run"].astype("int64")
        df["status"] = self.status
        df["message"] = self.messages
        return df

    def __repr__(self) -> str:
        n_ok = self.status.count("ok")
        return (
            f"satsim.CampaignResult({len(self)} runs: {n_ok} ok, {len(self) - n_ok} failed; "
            f"{len(self.columns)} columns)"
        )


def _shard(shard: Any) -> Optional["tuple[int, int]"]:
    """``None``, ``(i, n)`` or ``"i/n"`` as ``(i, n)``."""
    if shard is None:
        return None
    if isinstance(shard, str):
        i, sep, n = shard.partition("/")
        try:
            return int(i), int(n)
        except ValueError:
            raise SatsimError(f"shard: expected I/N (such as 0/4), got {shard!r}") from None
    i, n = shard
    return int(i), int(n)


def campaign(
    scene: PathLike,
    threads: Optional[int] = None,
    shard: Optional[Union[str, "tuple[int, int]"]] = None,
    *,
    base_dir: Optional[PathLike] = None,
    controller: Optional[Callable[["Run"], Any]] = None,
    period: Optional[float] = None,
    metrics: Optional[Callable[["Run", Trajectory], Mapping[str, float]]] = None,
    out: Optional[PathLike] = None,
    workers: Optional[int] = None,
    executor: Any = None,
    resume: bool = False,
    max_rows: Optional[int] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> CampaignResult:
    """A Monte Carlo campaign (contract sections 8 and 15): ``runs.csv`` as a table.

    ``scene`` is the path or the text of a scene with a ``[campaign]`` table (``base_dir``
    anchors a text's relative paths). ``shard``: ``(i, n)`` or ``"i/n"`` makes only the runs
    ``k`` with ``k % n == i``; the shards' rows together are the whole campaign's (run ``k``
    depends on ``(seed, k)`` alone). A run that fails is a row with status ``failed``, not an
    error; bad input raises :class:`SatsimError` with the command line's message. With
    flexible bodies, each run's ``peak_deflection_<body>`` is its largest deflection over every
    step as a fraction of its length (a beam's tip; a modes file's node for its distance from
    the body's frame); where finished runs passed 0.1 (beyond what the
    modal model holds) a :class:`UserWarning` says how many, as ``satsim campaign`` warns; so
    for runs whose energy budget drifted and for runs of an explicit adaptive method whose
    steps its stability limit held (``stability_held`` 1), not the tolerance.

    **The built-in controllers** (no ``controller``): as ``satsim campaign`` runs it, on
    ``threads`` threads (default every core), in memory. Ctrl-C stops it (no run starts, the
    running ones stop at their next output row) and raises ``KeyboardInterrupt``.

    **Your flight software** (``controller=``, ``period=``, contract section 15)::

        def make_fsw(run):              # run: satsim.Run: .index (k), .seed, .values
            return MyFsw(gain=2.0)
        class MyFsw:
            def step(self, t, meas, row):   # sim.measure(), sim.row() (the truth)
                return {"wheel_x": 0.01}    # inputs by name; {} leaves them as they are

        res = satsim.campaign("scene.toml", controller=make_fsw, period=0.1,
                              out="out/mc", workers=4)
        res.table                           # runs.csv

    Run ``k`` draws the values and the sensor seed ``satsim campaign`` draws for it, builds
    its controller with ``controller(run)`` and steps the drawn scene as
    :class:`Simulation` does: at ``t = t0, t0 + period, ...`` ``inputs = fsw.step(t,
    measurements, row)`` (called from the native side, no Python loop around it), then
    ``set_inputs(inputs)`` and an advance to the next instant (the last piece ends at the
    scene's end). Its rows are reduced as ``satsim campaign`` reduces them, so a controller
    that returns ``{}`` gives ``satsim campaign``'s rows bit for bit (with a fixed-step
    integrator and ``period`` a whole number of its steps; within the tolerance otherwise).

    - ``metrics(run, trajectory) -> dict`` (optional): more columns of ``runs.csv`` after
      the statistics (settling time, RMS error over a window...), with their percentiles in
      ``summary.json``; every run must return the same keys (letters, digits, ``_``) with
      finite values, in the same order.
    - ``out``: the folder, written as ``satsim campaign`` writes it (``runs.csv``,
      ``traces.csv``, ``summary.json``, ``campaign.json``, the plots); rows are streamed as
      runs finish and sorted at the end. ``None``: a temporary folder, removed after.
      ``resume=True`` continues the campaign in ``out`` (its finished runs are kept; it
      must have been made with the same scene, shard, controller, period and metrics).
    - ``workers=N``: N worker processes (the factory and ``metrics`` must be importable,
      as for :mod:`multiprocessing`); ``executor=``: any :class:`concurrent.futures.Executor`
      (a Dask ``Client.get_executor()``, Ray's); neither: this process. The files are the
      same bytes whatever ran them.
    - A controller (or factory, or ``metrics``) that raises, returns an unknown input name,
      a non-finite or out-of-range value makes that run ``failed``, its message naming the
      run, the time and the cause (the exception's last line); the other runs go on.
    - Ctrl-C keeps every finished run in ``out`` (worker processes are stopped, an
      executor's pending runs cancelled) and raises ``KeyboardInterrupt``; ``resume=True``
      goes on.
    - ``progress(done, total)`` is called after each run; ``max_rows`` bounds a run's rows.
    """
    if controller is None:
        extra = {"period": period, "metrics": metrics, "out": out, "workers": workers,
                 "executor": executor, "progress": progress, "max_rows": max_rows}
        given = [k for k, v in extra.items() if v is not None] + (["resume"] if resume else [])
        if given:
            raise SatsimError(
                f"{', '.join(given)} need{'s' if len(given) == 1 else ''} controller= "
                "(your flight software); the built-in controllers' campaign takes threads "
                "and shard (or use `satsim campaign` for its folder)")
        origin, text = _scene_args(scene, base_dir)
        columns, data, status, messages = _satsim.campaign(origin, text, threads, _shard(shard))
        return _warn_beyond(CampaignResult(columns, data, status, messages))
    if period is None:
        raise SatsimError("controller= needs period= (s): the control instants are "
                          "t0, t0 + period, t0 + 2 period, ...")
    if threads is not None:
        raise SatsimError("threads= is the built-in controllers' campaign's: with controller=, "
                          "give workers= (processes) or executor=")
    return _warn_beyond(_stepped.campaign(
        scene, controller=controller, period=period, metrics=metrics, out=out,
        workers=workers, executor=executor, resume=resume, shard=shard, base_dir=base_dir,
        max_rows=max_rows, progress=progress))


def _warn_beyond(res: CampaignResult) -> CampaignResult:
    """``res``, after a :class:`UserWarning` where finished runs bent a flexible body past a
    tenth of its length (a ``peak_deflection_<body>`` column past ``SMALL_DEFLECTION``), in ``satsim
    campaign``'s words."""
    peaks = [c for c in res.columns if c.startswith("peak_deflection_")]
    past = np.zeros(len(res), dtype=bool)
    for c in peaks:
        # A failed run's NaN is not past.
        past |= np.nan_to_num(res[c]) > _satsim.SMALL_DEFLECTION
    if past.any():
        warnings.warn(
            _satsim.beyond_warning(int(past.sum()), int(res.ok.sum())), UserWarning, stacklevel=3
        )
    # An energy budget that moved beyond the integration's error, counted as the command
    # line counts it.
    columns = list(res.columns)
    drifted = sum(
        _satsim.budget_drifted_row(columns, [float(x) for x in res.data[i]])
        for i in np.flatnonzero(res.ok)
    )
    if drifted:
        warnings.warn(
            _satsim.budget_warning(int(drifted), int(res.ok.sum())), UserWarning, stacklevel=3
        )
    # Steps held by an explicit method's stability limit, not the tolerance (a failed run's
    # NaN is not held).
    if "stability_held" in res.columns:
        held = int((np.nan_to_num(res["stability_held"]) == 1.0).sum())
        if held:
            warnings.warn(
                _satsim.held_warning(held, int(res.ok.sum())), UserWarning, stacklevel=3
            )
    return res


def modes(scene: PathLike, *, base_dir: Optional[PathLike] = None) -> Dict[str, Any]:
    """The structural modes of a scene at its initial state, as ``satsim modes`` (contract
    section 9): a dict with ``frequencies_hz`` (ascending) and ``damping_ratios`` (numpy
    arrays), ``rigid_modes`` (int), ``modes`` (a list of dicts: ``frequency_hz``,
    ``damping_ratio``, ``eigenvalue`` ``[re, im]``, ``shape`` and ``shape_imag``
    ``{state name: value}``), ``real_eigenvalues``, ``locked`` and ``released``."""
    return _satsim.modes(*_scene_args(scene, base_dir))


def linearize(scene: PathLike, *, base_dir: Optional[PathLike] = None) -> Dict[str, Any]:
    """The linear model ``dz/dt = A z + B u`` of a scene at its initial state, as ``satsim
    linearize`` (contract section 9): a dict with ``states`` and ``inputs`` (lists of str),
    ``A`` and ``B`` (2-D numpy arrays), ``error_estimate``, ``locked``, ``released`` and
    ``residual`` (``dz/dt`` at the point, by state: zero at an equilibrium; a numpy array)."""
    return _satsim.linearize(*_scene_args(scene, base_dir))


class Simulation:
    """A scene stepped from your code: flight software in the loop (contract section 13).

    ::

        sim = satsim.Simulation("scene.toml")   # a path or the scene's text; base_dir= as run()
        sim.t                                   # s
        sim.columns                             # the trajectory's columns (trajectory.csv's)
        sim.row()                               # dict: those columns at sim.t (the truth)
        sim.inputs                              # e.g. "torque_h4", "wheel_x", "thrust_roll"
        sim.set_inputs({"wheel_x": 0.01})       # held until changed (zero-order hold)
        events = sim.advance(0.1)               # [(t, effect, text)] that fired on the way
        sim.measure()                           # every sensor's latest reading
        r = sim.trajectory()                    # the rows so far, a Trajectory as run() gives
        sim.close()                             # or use ``with satsim.Simulation(...) as sim:``

    ``advance(dt)`` integrates from ``t`` to ``t + dt`` with the scene's integrator, events
    handled inside. A fixed-step method (``rk4``) takes steps of its ``step`` on the grid from
    the start, the last one shortened to land on ``t + dt``; an end within round-off of an
    output time or a grid point is that point. With the inputs never set, stepping to the end
    in any pieces gives ``satsim.run``'s rows: to the last bit for a fixed-step method when
    every piece is a whole number of steps, within the tolerance for an adaptive one. The GIL
    is released while it integrates.

    Inputs (the linear model's, ``satsim.linearize``): ``torque_<hinge>`` for each model
    hinge, a torque added to the initial state's constant ``torque`` (held, it acts exactly
    as that constant would); and ``wheel_<name>`` for each reaction wheel, a motor command
    (N m) added to the wheel's command (the attitude controller's, or its ``torque`` key)
    before its torque and speed limits. Beyond the linear model's: ``dipole_<torquer>`` for
    each magnetic torquer (A m², added to its command before its clamp) and
    ``thrust_<thruster>`` for each thruster, a duty cycle in [0, 1] added to its ``duty`` key
    and latched at the first period start at or after the time it is set (so a loop advancing
    by whole periods commands each period from its start). Inputs are held until changed and
    added to what the enabled effects apply.

    Rows are recorded as in a run, on the scene's ``output.every`` grid. :meth:`advance` may go
    on past the scene's end (:attr:`t_end`: a closed loop often runs longer than the nominal
    ``duration``): the rows continue on the same grid, and nothing else changes. The rows are
    kept in memory for :meth:`trajectory`, at most ``max_rows`` of them (default 1 000 000,
    ``satsim run --max-rows``' default), the first included: an ``advance`` that would record
    more raises :class:`SatsimError` before it integrates and changes nothing (so memory never
    grows with ``dt``); raise ``output.every`` in the scene or ``max_rows`` to go on. With
    ``out=DIR`` they are also streamed to ``DIR/trajectory.csv`` as ``satsim run`` writes it;
    :meth:`close` then writes ``events.csv``, the plots the scene asks for and ``view.html``
    (when the scene's view is on) beside it.

    Bad input raises :class:`SatsimError` and changes nothing: an unknown input name, a
    non-finite input value, a thruster's duty outside [0, 1], a ``dt`` that is not a finite
    number > 0 or that would keep more than ``max_rows`` rows. A failed integration
    raises :class:`SatsimError`; the simulation cannot go on after it.

    ``measure()`` returns every sensor's latest reading (the scene's ``[sensors]``: gyros,
    star trackers, Sun sensors, magnetometers, contract section 13), by sensor name and by
    column name. ``seed=`` replaces the scene's ``[sensors] seed`` (e.g. a Gymnasium
    ``reset(seed=...)`` drawing new noise); a scene without sensors ignores it.
    """

    __slots__ = ("_native", "_columns")

    #: The default of ``max_rows``: ``satsim run --max-rows``' default.
    MAX_ROWS = 1_000_000

    def __init__(
        self,
        scene: PathLike,
        out: Optional[PathLike] = None,
        *,
        base_dir: Optional[PathLike] = None,
        seed: Optional[int] = None,
        max_rows: int = MAX_ROWS,
    ) -> None:
        origin, text = _scene_args(scene, base_dir)
        out_path = None if out is None else os.fspath(out)
        if seed is not None:
            if isinstance(seed, bool) or not isinstance(seed, int):
                raise SatsimError(f"seed must be an integer, got {seed!r}")
            if not 0 <= seed < 2**64:
                raise SatsimError(f"seed must be an integer in [0, 2**64), got {seed}")
        if isinstance(max_rows, bool) or not isinstance(max_rows, int):
            raise SatsimError(f"max_rows must be an integer, got {max_rows!r}")
        if not 1 <= max_rows < 2**64:
            raise SatsimError(f"max_rows must be an integer in [1, 2**64), got {max_rows}")
        self._native = _satsim.NativeSimulation(origin, text, out_path, seed, max_rows)
        self._columns: List[str] = list(self._native.columns)

    @property
    def t(self) -> float:
        """The time (s)."""
        return float(self._native.t)

    @property
    def columns(self) -> List[str]:
        """The trajectory's column names (``satsim run``'s ``trajectory.csv`` header)."""
        return list(self._columns)

    @property
    def t_end(self) -> float:
        """The scene's end, its start plus ``duration`` (s): where ``satsim.run`` stops.
        :meth:`advance` may go on past it (the rows continue on the same grid)."""
        return float(self._native.t_end)

    @property
    def sensor_kinds(self) -> Dict[str, str]:
        """Each sensor's kind by its name, in the scene's order: ``"gyro"``,
        ``"star_tracker"``, ``"sun_sensor"`` or ``"magnetometer"``."""
        return dict(self._native.sensors)

    @property
    def max_rows(self) -> int:
        """The most rows kept for :meth:`trajectory` (the first included)."""
        return int(self._native.max_rows)

    @property
    def inputs(self) -> List[str]:
        """The input names: ``torque_<hinge>`` per model hinge, ``wheel_<name>`` per wheel."""
        return list(self._native.inputs)

    @property
    def work(self) -> Dict[str, int]:
        """The integrator's work over the :meth:`advance` calls so far, as ``satsim run``
        counts a run's: ``rhs_evals`` (right-hand sides, a finite-difference Jacobian's
        included), ``steps_accepted``, ``steps_rejected``, ``steps_capped`` (the accepted
        steps an adaptive method cut to land on a call's end or a time stop),
        ``jacobian_evals``, ``jacobian_updates`` (Jacobians brought to a new state through
        the mass matrix, on a tree with flexible bodies) and ``lu_decompositions`` (Radau
        IIA). Each call goes on from the
        last with its step and Jacobian, so a short ``dt`` costs a step or two."""
        return {k: int(v) for k, v in self._native.work}

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` was called."""
        return bool(self._native.closed)

    def row(self) -> Dict[str, float]:
        """The columns at :attr:`t` (the true state, not a measurement), as a dict."""
        return dict(zip(self._columns, self._native.row()))

    def set_inputs(self, values: Mapping[str, float]) -> None:
        """Sets inputs by name, held until changed. An unknown name or a non-finite value
        raises :class:`SatsimError` and sets none of them; so does ``values`` that is not a
        mapping, or a value that is not a number (a string such as ``"1"`` included)."""
        if not isinstance(values, Mapping):
            raise SatsimError(
                f"set_inputs takes a mapping of input names to numbers, got {values!r}")
        pairs: List[Tuple[str, float]] = []
        for name, value in values.items():
            if not isinstance(name, str):
                raise SatsimError(f"input names are strings, got {name!r}")
            if isinstance(value, (str, bytes)):
                raise SatsimError(f"input `{name}` must be a number, got {value!r}")
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise SatsimError(f"input `{name}` must be a number, got {value!r}") from None
            pairs.append((name, v))
        self._native.set_inputs(pairs)

    def advance(self, dt: float) -> List[Tuple[float, str, str]]:
        """Integrates from :attr:`t` to ``t + dt``; returns the events that fired, as
        ``(t, effect, text)``. ``dt`` must be a finite number > 0 whose rows fit in what is
        left of ``max_rows``; ``t + dt`` may lie past :attr:`t_end`."""
        try:
            dt = float(dt)
        except (TypeError, ValueError):
            raise SatsimError(f"dt must be a number, got {dt!r}") from None
        return [(float(t), e, what) for t, e, what in self._native.advance(dt)]

    def measure(self) -> Dict[str, Union[float, List[float]]]:
        """Every sensor's latest reading at :attr:`t`: for each sensor, its name -> the
        reading as a list (gyro, Sun sensor, magnetometer ``[x, y, z]`` in the body's axes, in
        rad/s, a unit vector, T; star tracker ``[w, x, y, z]``, body to inertial, ``w >= 0``),
        and each of its columns -> a float (``"gyro_x"``, ``"st_q_w"``: the trajectory's
        columns). Each is the reading last taken (sensors sample every ``period`` from the
        start, so there is always one); an empty dict for a scene without sensors.

        ::

            m = sim.measure()
            m["gyro"]      # [wx, wy, wz]
            m["gyro_x"]    # wx
        """
        out: Dict[str, Union[float, List[float]]] = {}
        # As the trajectory's columns: a quaternion, a GPS's position and velocity, a
        # vector; a single value (a coarse Sun sensor, a star tracker's `_valid`) has none.
        suffixes = {
            1: (),
            4: ("_q_w", "_q_x", "_q_y", "_q_z"),
            6: ("_x", "_y", "_z", "_vx", "_vy", "_vz"),
        }
        for name, values in self._native.measure():
            reading = [float(v) for v in values]
            out[name] = reading
            for suffix, v in zip(suffixes.get(len(reading), ("_x", "_y", "_z")), reading):
                out[name + suffix] = v
        return out

    def trajectory(self) -> Trajectory:
        """The rows so far, as :func:`run` returns them (at most ``max_rows``)."""
        columns, data = self._native.trajectory()
        return Trajectory(columns, data)

    def close(self) -> None:
        """Ends the simulation and, with ``out=DIR``, writes the rest of the folder
        (``events.csv``, the plots, ``view.html``). Calling it again does nothing; after
        it, :meth:`advance` and :meth:`set_inputs` raise :class:`SatsimError`. What
        ``satsim run`` warns of after a run is a :class:`UserWarning` here, for the steps
        taken: a flexible beam bent past a tenth of its length (beyond what its modal model
        holds), an energy budget that did not close, and steps of ``dp54`` or ``dop853``
        held by their stability limit on the scene's fastest motion (weighed over the
        advances the integrator took in more than one step: a ``dt`` below the limit sets
        the steps itself)."""
        said = [] if self._native.closed else self._native.warnings()
        self._native.close()
        for w in said:
            warnings.warn(w, UserWarning, stacklevel=2)

    def __enter__(self) -> "Simulation":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<satsim.Simulation t={self.t} inputs={self.inputs}>"


from . import _stepped  # noqa: E402  (uses the classes above)
from ._stepped import Run  # noqa: E402
from . import fsw  # noqa: E402,F401  (satsim.fsw.Mekf without another import)
