"""The notebook-style example runs end to end (needs matplotlib)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from conftest import ROOT


def test_deploy_example(tmp_path):
    pytest.importorskip("matplotlib", reason="the example plots with matplotlib")
    p = subprocess.run([sys.executable, ROOT / "examples/python/deploy.py", tmp_path],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "satsim.Trajectory(301 rows" in p.stdout
    assert "Hz   damping ratio" in p.stdout
    png = tmp_path / "deploy.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_fsw_in_the_loop_example(tmp_path):
    """examples/python/fsw_in_the_loop.py over 20 s: the Python law on the truth reproduces
    the built-in discrete controller (the script exits non-zero above 1e-12), and the law on
    the sensors runs and plots."""
    pytest.importorskip("matplotlib", reason="the example plots with matplotlib")
    p = subprocess.run([sys.executable, ROOT / "examples/python/fsw_in_the_loop.py", tmp_path,
                        "--duration", "20"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "Python law on the truth against the built-in discrete controller" in p.stdout
    assert "Python, sensors" in p.stdout
    png = tmp_path / "fsw_in_the_loop.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_flexible_array_example(tmp_path):
    """examples/python/flexible_array.py: both deployments run, the flexible one latches later
    with bent panels and keeps its energy budget, and the plot is written."""
    pytest.importorskip("matplotlib", reason="the example plots with matplotlib")
    p = subprocess.run([sys.executable, ROOT / "examples/python/flexible_array.py", tmp_path],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    rows = {line[:40].strip(): line[40:].split() for line in p.stdout.splitlines()
            if len(line) > 40}
    rigid, flexible = (float(v) for v in rows["h4 latches (s)"])
    assert flexible > rigid + 0.05, (rigid, flexible)
    assert float(rows["largest |tip_panel1| (mm)"][1]) > 10.0
    drift = float(p.stdout.split("energy budget drift (flexible): ")[1].split()[0])
    assert drift < 1e-6 * 19.7
    assert (tmp_path / "flexible_array.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
