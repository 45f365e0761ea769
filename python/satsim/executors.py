"""Executors for :func:`satsim.campaign`'s ``executor=`` beyond the standard library's.

Any :class:`concurrent.futures.Executor` runs a campaign stepped by your flight software:
a process pool, a Dask ``Client.get_executor()``, or Ray's through :class:`RayExecutor`
(Ray has no ``concurrent.futures`` executor of its own; each ``ObjectRef`` has a future).
"""

from __future__ import annotations

import concurrent.futures as cf
import threading
from typing import Any, Callable, Dict


class RayExecutor(cf.Executor):
    """Ray tasks as a :class:`concurrent.futures.Executor`: ``submit(fn, *args)`` runs
    ``fn`` as a Ray task (``ray.remote(**options)``, one CPU each by default) and returns its
    ``ObjectRef``'s future. Ray must be initialised (``ray.init()``: a local cluster, or
    ``ray.init(address=...)``); the functions must be importable on the workers.

    ::

        import ray, satsim
        from satsim.executors import RayExecutor
        ray.init()
        satsim.campaign("mc.toml", controller=make_fsw, period=0.1, out="out/mc",
                        executor=RayExecutor())

    ``shutdown(cancel_futures=True)`` (what Ctrl-C in a campaign calls) cancels the tasks
    not finished (``ray.cancel``).
    """

    def __init__(self, **options: Any) -> None:
        import ray  # noqa: F401  (fails early without Ray)

        self._options: Dict[str, Any] = {"num_cpus": 1, **options}
        self._remote: Dict[Callable[..., Any], Any] = {}
        self._refs: Dict[cf.Future, Any] = {}
        self._lock = threading.Lock()

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future:
        import ray

        with self._lock:
            remote = self._remote.get(fn)
            if remote is None:
                remote = self._remote[fn] = ray.remote(**self._options)(fn)
            ref = remote.remote(*args, **kwargs)
            future = ref.future()
            self._refs[future] = ref
            future.add_done_callback(self._forget)
            return future

    def _forget(self, future: cf.Future) -> None:
        with self._lock:
            self._refs.pop(future, None)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        import ray

        with self._lock:
            refs = list(self._refs.values()) if cancel_futures else []
        for ref in refs:
            try:
                ray.cancel(ref, force=True)
            except Exception:  # pragma: no cover - finished meanwhile
                pass
