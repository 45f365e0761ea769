"""examples/python/fsw_campaign.py, shortened: a Monte Carlo campaign of a Python control law
(satsim.campaign with controller=, contract section 15) on two worker processes writes the
campaign folder with the example's metrics as runs.csv columns, and the envelope plot."""

from __future__ import annotations

import csv
import inspect
import json
import math
import subprocess
import sys

import pytest

import satsim
from conftest import ROOT

METRICS = ("settling_time", "rms_pointing_arcsec", "peak_wheel_speed")


def _takes_controller() -> bool:
    try:
        return "controller" in inspect.signature(satsim.campaign).parameters
    except (TypeError, ValueError):
        return False


def test_fsw_campaign_example(tmp_path):
    if not _takes_controller():
        pytest.skip("this satsim's campaign() takes no controller= (Monte Carlo of your own "
                    "flight software, contract section 15): the example needs it")
    pytest.importorskip("matplotlib", reason="the example plots with matplotlib")
    out = tmp_path / "campaign"
    p = subprocess.run([sys.executable, ROOT / "examples/python/fsw_campaign.py", out,
                        "--runs", "4", "--duration", "5", "--workers", "2"],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "4 runs: 4 ok, 0 failed" in p.stdout, p.stdout

    with open(out / "runs.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["run"] for r in rows] == ["0", "1", "2", "3"]
    assert [r["status"] for r in rows] == ["ok"] * 4, [r["message"] for r in rows]
    for name in METRICS:
        assert name in rows[0], list(rows[0])
        for r in rows:
            assert math.isfinite(float(r[name])), (name, r[name])
    for r in rows:
        assert 0.0 <= float(r["settling_time"]) <= 5.0
        assert float(r["rms_pointing_arcsec"]) >= 0.0
        assert float(r["peak_wheel_speed"]) >= 0.0
    # The scene's dispersed values are columns too.
    assert "initial.base.angular_velocity[0]" in rows[0]
    assert "sensors.star_tracker.0.noise_arcsec[2]" in rows[0]

    summary = json.loads((out / "summary.json").read_text())
    assert (summary["runs"], summary["ok"], summary["failed"]) == (4, 4, 0)
    assert (out / "traces.csv").stat().st_size > 0
    assert (out / "fsw_campaign.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
