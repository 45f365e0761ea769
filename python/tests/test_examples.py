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
