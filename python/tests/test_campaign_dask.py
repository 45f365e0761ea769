"""`examples/python/campaign_dask.py` on a `dask.distributed.LocalCluster` with two worker
processes: the merged shards equal the single-process campaign to the last bit."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from conftest import EXAMPLES, ROOT, SCENES


def test_campaign_over_a_local_dask_cluster(tmp_path):
    pytest.importorskip("dask.distributed", reason="needs `pip install dask distributed`")
    # 12 runs of 2 s in 3 shards on 2 workers; the model beside it as `../satellite.toml`.
    text = (SCENES / "deploy_campaign.toml").read_text()
    text = text.replace("duration = 60.0", "duration = 2.0").replace("runs = 64", "runs = 12")
    (tmp_path / "scenes").mkdir()
    shutil.copy(EXAMPLES / "satellite.toml", tmp_path / "satellite.toml")
    scene = tmp_path / "scenes" / "small.toml"
    scene.write_text(text)
    p = subprocess.run(
        [sys.executable, ROOT / "examples/python/campaign_dask.py", scene,
         "--shards", "3", "--workers", "2"],
        capture_output=True, text=True, timeout=300, cwd=tmp_path,
    )
    assert p.returncode == 0, p.stdout + p.stderr
    assert "12 runs in 3 shards on 2 local workers: 12 ok, 0 failed" in p.stdout
    assert "merged == single process: yes (to the last bit)" in p.stdout
