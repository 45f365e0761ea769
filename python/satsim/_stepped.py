"""Monte Carlo of your own flight software (contract section 15): a campaign whose runs are
stepped by a controller written in Python, in this process, in worker processes, or on any
``concurrent.futures.Executor`` (a Dask client's, Ray's).

Run ``k`` draws the values and the sensor seed ``satsim campaign`` draws for it; the native
side (``NativeCampaign.run_stepped``) builds the drawn scene, calls the controller's
``step(t, measurements, row)`` at ``t0 + i * period`` from Rust (no Python loop around it),
sets the inputs it returns and reduces the rows to ``satsim campaign``'s record. Workers send
records back as plain tuples (pickled bit for bit); this process alone writes the folder
(``NativeFolder``), which sorts the rows when it finishes: the files are the same bytes
whatever made the runs and in whatever order they finished.
"""

from __future__ import annotations

import concurrent.futures as cf
import os
import signal
import sys
import tempfile
from typing import Any, Callable, Dict, Iterator, List, Mapping, Optional, Tuple

from . import _satsim

SatsimError = _satsim.SatsimError

#: Each process's campaigns, by ``(origin, text, max_rows)``: a worker reads a campaign once.
_CAMPAIGNS: Dict[Tuple[str, Optional[str], Optional[int]], Any] = {}


class Run:
    """What the controller factory (and ``metrics``) learn of run ``k``.

    ``index``: ``k``, the run number (``runs.csv``'s ``run``); ``seed``: the run's sensor
    seed (its scene's ``[sensors] seed``, drawn from the campaign's seed and ``k``);
    ``values``: the drawn values, keyed as ``runs.csv``'s columns
    (``{"initial.base.angular_velocity[0]": 0.0012, ...}``), as the run uses them.
    """

    __slots__ = ("index", "seed", "values")

    def __init__(self, index: int, seed: int, values: Mapping[str, float]) -> None:
        self.index: int = int(index)
        self.seed: int = int(seed)
        self.values: Dict[str, float] = dict(values)

    def __repr__(self) -> str:
        return f"satsim.Run(index={self.index}, seed={self.seed}, values={self.values!r})"

    def __reduce__(self) -> Any:
        return (Run, (self.index, self.seed, self.values))


def _native(spec: Tuple[str, Optional[str], Optional[int]]) -> Any:
    c = _CAMPAIGNS.get(spec)
    if c is None:
        if len(_CAMPAIGNS) >= 4:
            _CAMPAIGNS.clear()
        c = _CAMPAIGNS[spec] = _satsim.NativeCampaign(*spec)
    return c


def _last_line(e: BaseException) -> str:
    """The exception as a traceback's last line: ``ValueError: boom``."""
    text = " ".join(str(e).split())
    return f"{type(e).__name__}: {text}" if text else type(e).__name__


def _metrics_items(m: Any) -> List[Tuple[str, float]]:
    if not isinstance(m, Mapping):
        raise TypeError(f"metrics must return a dict of numbers, got {type(m).__name__}")
    items = []
    for name, value in m.items():
        if not isinstance(name, str):
            raise TypeError(f"a metric's name must be a string, got {name!r}")
        try:
            items.append((name, float(value)))
        except (TypeError, ValueError):
            raise TypeError(f"the metric `{name}` is {value!r}, not a number") from None
    return items


def run_one(
    spec: Tuple[str, Optional[str], Optional[int]],
    k: int,
    factory: Callable[[Run], Any],
    period: float,
    metrics: Optional[Callable[[Run, Any], Mapping[str, float]]] = None,
) -> tuple:
    """Makes run ``k`` of the campaign ``spec`` with ``factory(run)``'s controller: its
    record (a tuple for ``NativeFolder.emit``). Any process; what the workers execute."""
    from . import Trajectory

    c = _native(spec)
    run = Run(k, c.sensor_seed(k), dict(zip(c.dispersed, c.draw(k))))
    try:
        fsw = factory(run)
    except Exception as e:  # the run fails, the campaign goes on
        return c.failed(k, f"run {k}: the controller factory raised {_last_line(e)}")
    rec, rows = c.run_stepped(k, fsw, period)
    if metrics is not None and rows is not None:
        try:
            items = _metrics_items(metrics(run, Trajectory(*rows)))
        except Exception as e:
            return c.failed(k, f"run {k}: the metrics raised {_last_line(e)}")
        rec = rec[:-1] + (items,)  # the metrics come last
    return rec


def _worker_init() -> None:
    """Worker processes leave Ctrl-C to the process that drives them (it stops them)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _qualified(f: Any, what: str) -> str:
    module = getattr(f, "__module__", None) or "?"
    name = getattr(f, "__qualname__", None) or getattr(type(f), "__qualname__", "?")
    if not callable(f):
        raise SatsimError(f"{what} must be callable, got {type(f).__name__}")
    return f"{module}:{name}"


def _read_table(path: str) -> Any:
    """``runs.csv`` as a :class:`satsim.CampaignResult`."""
    import csv

    import numpy as np

    from . import CampaignResult

    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    status_at, message_at = header.index("status"), header.index("message")
    data = np.empty((len(rows), len(header)), dtype=np.float64)
    status, messages = [], []
    for i, r in enumerate(rows):
        for j, v in enumerate(r):
            if j == status_at:
                data[i, j] = 1.0 if v == "ok" else 0.0
            elif j == message_at:
                data[i, j] = np.nan
            else:
                data[i, j] = float(v) if v else np.nan
        status.append(r[status_at])
        messages.append(r[message_at])
    return CampaignResult(header, data, status, messages)


def _stop_pool(pool: cf.Executor) -> None:
    """Stops a process pool now: no run starts, the running ones end with their processes."""
    for p in list((getattr(pool, "_processes", None) or {}).values()):
        try:
            p.terminate()
        except Exception:  # pragma: no cover - already gone
            pass
    pool.shutdown(wait=False, cancel_futures=True)


def campaign(
    scene: Any,
    *,
    controller: Callable[[Run], Any],
    period: float,
    metrics: Optional[Callable[[Run, Any], Mapping[str, float]]] = None,
    out: Any = None,
    workers: Optional[int] = None,
    executor: Optional[cf.Executor] = None,
    resume: bool = False,
    shard: Any = None,
    base_dir: Any = None,
    max_rows: Optional[int] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> Any:
    """The body of :func:`satsim.campaign` with a ``controller``; see its documentation."""
    from . import _scene_args, _shard

    origin, text = _scene_args(scene, base_dir)
    if text is None:
        # Workers parse the text this process read, so that a file edited meanwhile cannot
        # give runs of two scenes (its model and other files are still read where they lie).
        try:
            with open(origin, encoding="utf-8") as f:
                text = f.read()
        except OSError as e:
            raise SatsimError(f"{origin}: cannot read the scene: {e.strerror or e}") from None
    if max_rows is not None and (isinstance(max_rows, bool) or not isinstance(max_rows, int)
                                 or max_rows < 1):
        raise SatsimError(f"max_rows must be a whole number >= 1, got {max_rows!r}")
    spec = (origin, text, max_rows)
    native = _native(spec)
    try:
        period = float(period)
    except (TypeError, ValueError):
        raise SatsimError(f"period must be a number (s), got {period!r}") from None
    native.check_period(period)
    identity = _satsim.NativeCampaign.identity(
        _qualified(controller, "controller"), period,
        None if metrics is None else _qualified(metrics, "metrics"))
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise SatsimError(f"workers must be a whole number >= 1, got {workers!r}")
    if workers is not None and executor is not None:
        raise SatsimError("give workers= or executor=, not both")

    tmp = None
    if out is None:
        if resume:
            raise SatsimError("resume=True needs the folder to resume: out=")
        tmp = tempfile.TemporaryDirectory(prefix="satsim-campaign-")
        folder_path = tmp.name
    else:
        folder_path = os.fspath(out)
    try:
        folder = _satsim.NativeFolder(native, folder_path, _shard(shard), resume, identity,
                                      metrics is not None)
        todo: List[int] = list(folder.todo)
        total = len(todo) + folder.skipped
        made = folder.skipped

        def emit(rec: tuple) -> None:
            nonlocal made
            folder.emit(rec)
            made += 1
            if progress is not None:
                progress(made, total)

        args = (period, metrics)
        own_pool = None
        if executor is None and workers is not None and workers > 1:
            own_pool = cf.ProcessPoolExecutor(max_workers=workers, initializer=_worker_init)
            executor = own_pool
        try:
            if executor is None:
                for k in todo:
                    emit(run_one(spec, k, controller, *args))
            else:
                _drive(executor, spec, todo, controller, args, emit,
                       window=4 * (workers or getattr(executor, "_max_workers", None) or 8))
        except KeyboardInterrupt:
            if own_pool is not None:
                _stop_pool(own_pool)
                own_pool = None
            left = len(todo) - (made - folder.skipped)
            where = os.path.join(folder_path, "runs.csv")
            raise KeyboardInterrupt(
                f"interrupted: {made} runs in {where}, {left} not run; continue with resume=True"
            ) from None
        finally:
            if own_pool is not None:
                own_pool.shutdown(wait=True)
        folder.close()
        result = _read_table(os.path.join(folder_path, "runs.csv"))
        result.out = None if tmp is not None else folder_path
        return result
    finally:
        if tmp is not None:
            tmp.cleanup()


def _drive(executor: cf.Executor, spec: tuple, todo: List[int], controller: Any,
           args: tuple, emit: Callable[[tuple], None], window: int) -> None:
    """Runs ``todo`` on ``executor``, at most ``window`` in flight, each record to ``emit``
    as it comes; on any exit pending runs are cancelled."""
    queue: Iterator[int] = iter(todo)
    pending: Dict[cf.Future, int] = {}

    def submit() -> bool:
        k = next(queue, None)
        if k is None:
            return False
        try:
            f = executor.submit(run_one, spec, k, controller, *args)
        except Exception as e:
            raise SatsimError(_unsendable(e)) from e
        pending[f] = k
        return True

    try:
        while len(pending) < window and submit():
            pass
        while pending:
            done, _ = cf.wait(list(pending), return_when=cf.FIRST_COMPLETED)
            for f in done:
                k = pending.pop(f)
                try:
                    rec = f.result()
                except Exception as e:
                    raise SatsimError(
                        f"run {k} could not be made by the executor: {_last_line(e)}"
                        + ("" if "pickl" not in str(e).lower() else f" ({_unsendable(e)})")
                    ) from e
                emit(rec)
                submit()
    finally:
        for f in pending:
            f.cancel()


def _unsendable(e: BaseException) -> str:
    return (
        f"the controller factory (or metrics) cannot be sent to the workers: {_last_line(e)}; "
        "it must be importable, as for multiprocessing: a function or class defined at the top "
        "level of a module (not a lambda, nor a function defined in another function)"
    )


def main(argv: Optional[List[str]] = None) -> int:
    """``python -m satsim campaign SCENE --controller MODULE:FACTORY --period P ...``."""
    import argparse
    import importlib

    ap = argparse.ArgumentParser(
        prog="python -m satsim campaign",
        description="A Monte Carlo campaign stepped by your flight software (contract "
                    "section 15); shards merge with `satsim campaign merge`.")
    ap.add_argument("scene", help="the scene, with a [campaign] table")
    ap.add_argument("--controller", required=True, metavar="MODULE:FACTORY",
                    help="factory(run) -> an object with step(t, measurements, row) -> dict")
    ap.add_argument("--period", required=True, type=float, help="control period (s)")
    ap.add_argument("--metrics", metavar="MODULE:FUNC",
                    help="metrics(run, trajectory) -> dict: more columns of runs.csv")
    ap.add_argument("--workers", type=int, help="worker processes (default: this process)")
    ap.add_argument("--shard", metavar="I/N",
                    help="only the runs k with k %% N == I (default: the scheduler's "
                         "environment: Slurm, Kubernetes with --shards, AWS Batch)")
    ap.add_argument("--shards", type=int, metavar="N",
                    help="the number of shards of a Kubernetes indexed Job")
    ap.add_argument("--resume", action="store_true", help="continue the folder's campaign")
    ap.add_argument("--out", help="output folder (default out/<scene stem>-campaign)")
    ap.add_argument("--max-rows", type=int, help="the most output rows one run may have")
    args = ap.parse_args(argv)

    def load(ref: str, what: str) -> Any:
        module, sep, name = ref.partition(":")
        if not sep or not module or not name:
            raise SatsimError(f"--{what}: expected MODULE:NAME, got {ref!r}")
        # The current folder is importable, as for `python -m`.
        if "" not in sys.path and os.getcwd() not in sys.path:
            sys.path.insert(0, os.getcwd())
        try:
            obj: Any = importlib.import_module(module)
        except ImportError as e:
            raise SatsimError(f"--{what}: cannot import {module}: {e}") from None
        for part in name.split("."):
            try:
                obj = getattr(obj, part)
            except AttributeError:
                raise SatsimError(f"--{what}: {module} has no {name}") from None
        return obj

    try:
        factory = load(args.controller, "controller")
        metrics = load(args.metrics, "metrics") if args.metrics else None
        i, n, source = _satsim.choose_shard(args.shard, args.shards)
        out = args.out
        if out is None:
            stem = os.path.splitext(os.path.basename(args.scene))[0]
            out = os.path.join("out", f"{stem}-campaign")
        if n > 1:
            print(f"shard {i}/{n} ({source})", file=sys.stderr)
        tty = sys.stderr.isatty()

        def progress(done: int, total: int) -> None:
            if tty:
                print(f"\r{done}/{total} runs", end="", file=sys.stderr, flush=True)

        res = campaign(args.scene, controller=factory, period=args.period, metrics=metrics,
                       out=out, workers=args.workers, resume=args.resume,
                       shard=(i, n), max_rows=args.max_rows, progress=progress)
        if tty:
            print(file=sys.stderr)
    except SatsimError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as e:
        print(f"\n{e}", file=sys.stderr)
        return 130
    n_ok = int(res.ok.sum())
    print(f"{len(res)} runs: {n_ok} ok, {len(res) - n_ok} failed; wrote {out}")
    return 0
