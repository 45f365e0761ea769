"""A Monte Carlo campaign spread over a Dask cluster: every worker runs one shard of the
campaign (`satsim.campaign(scene, shard=(i, n))`, the runs with k % n == i), the client merges
the shards into the table a single process writes, and checks it against one.

    python examples/python/campaign_dask.py [SCENE] [--shards N] [--workers W]
    python examples/python/campaign_dask.py SCENE --scheduler tcp://HOST:8786   # a real cluster

Without `--scheduler` it starts a `dask.distributed.LocalCluster` with W worker processes.
Run k draws its inputs from (seed, k) alone (contract section 8), so the merged table equals
the single-process one to the last bit whatever the sharding. The scene's paths must be
readable by the workers (a shared file system), or pass the scene's text instead of a path.

Needs: `pip install "./python[examples]"` (Dask, distributed, pandas and matplotlib).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import List, Tuple

import numpy as np

import satsim

ROOT = Path(__file__).resolve().parents[2]

Shard = Tuple[List[str], np.ndarray, List[str]]


def run_shard(scene: str, i: int, n: int) -> Shard:
    """One shard on a worker: `(columns, data, status)` (plain objects, cheap to pickle).
    One thread per shard: the cluster provides the parallelism."""
    c = satsim.campaign(scene, threads=1, shard=(i, n))
    return list(c.columns), np.asarray(c.data), list(c.status)


def merge(shards: List[Shard]) -> Shard:
    """The shards' rows in one table sorted by the run number, as `satsim campaign merge`."""
    columns = shards[0][0]
    if any(s[0] != columns for s in shards):
        raise ValueError("the shards have different columns")
    data = np.concatenate([s[1] for s in shards])
    status = [x for s in shards for x in s[2]]
    order = np.argsort(data[:, columns.index("run")], kind="stable")
    return columns, data[order], [status[k] for k in order]


def same(a: Shard, b: Shard) -> bool:
    """Equal to the last bit (NaN where a failed run has no statistics counts as equal)."""
    return (
        a[0] == b[0]
        and a[2] == b[2]
        and a[1].shape == b[1].shape
        and bool(np.array_equal(a[1].view(np.uint64), b[1].view(np.uint64)))
    )


def main(argv: List[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default=str(ROOT / "examples/scenes/deploy_campaign.toml"))
    ap.add_argument("--shards", type=int, default=4)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--scheduler", help="address of a running Dask scheduler")
    args = ap.parse_args(argv)

    from dask.distributed import Client, LocalCluster

    if args.scheduler:
        client = Client(args.scheduler)
        cluster = None
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True)
        client = Client(cluster)
    try:
        n = args.shards
        futures = client.map(run_shard, [args.scene] * n, range(n), [n] * n, pure=False)
        merged = merge(client.gather(futures))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

    single = run_shard(args.scene, 0, 1)
    ok = same(merged, single)
    status = merged[2]
    print(f"{len(status)} runs in {n} shards on {'the cluster' if args.scheduler else f'{args.workers} local workers'}: "
          f"{status.count('ok')} ok, {len(status) - status.count('ok')} failed")
    print("merged == single process:", "yes (to the last bit)" if ok else "NO")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
