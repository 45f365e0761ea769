"""`satsim.linearize` and `satsim.modes` against `satsim linearize` / `satsim modes` (bit for
bit), and a check of the modes against the linear model they come from."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import satsim
from conftest import SCENES

SCENE = SCENES / "deployment_modes.toml"


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def cli_json(cli, *args):
    return json.loads(subprocess.run([cli, *args], check=True, capture_output=True,
                                     text=True).stdout)


def test_linearize_equals_the_command_line(cli):
    want = cli_json(cli, "linearize", SCENE)
    got = satsim.linearize(SCENE)
    assert got["states"] == want["states"] and got["inputs"] == want["inputs"]
    assert got["A"].shape == (len(want["states"]), len(want["states"]))
    assert got["B"].shape == (len(want["states"]), len(want["inputs"]))
    np.testing.assert_array_equal(bits(got["A"]), bits(want["A"]))
    np.testing.assert_array_equal(bits(got["B"]), bits(want["B"]))
    assert got["error_estimate"] == want["error_estimate"]
    assert got["locked"] == want["locked"] and got["released"] == want["released"]
    assert len(got["residual"]) == len(want["states"])
    np.testing.assert_array_equal(bits(got["residual"]), bits(want["residual"]))


def test_modes_equal_the_command_line(cli):
    want = cli_json(cli, "modes", SCENE)
    got = satsim.modes(SCENE)
    np.testing.assert_array_equal(bits(got["frequencies_hz"]), bits(want["frequencies_hz"]))
    np.testing.assert_array_equal(bits(got["damping_ratios"]), bits(want["damping_ratios"]))
    assert got["rigid_modes"] == want["rigid_modes"]
    assert len(got["modes"]) == len(want["modes"])
    for g, w in zip(got["modes"], want["modes"]):
        assert g["frequency_hz"] == w["frequency_hz"]
        np.testing.assert_array_equal(bits(g["eigenvalue"]), bits(w["eigenvalue"]))
        assert g["shape"] == w["shape"]


def test_modes_are_eigenvalues_of_a():
    lin = satsim.linearize(SCENE)
    m = satsim.modes(SCENE)
    assert len(m["frequencies_hz"]) > 0
    assert np.all(np.diff(m["frequencies_hz"]) >= 0)
    lam = np.linalg.eigvals(lin["A"])
    for mode in m["modes"]:
        re, im = mode["eigenvalue"]
        assert mode["frequency_hz"] == pytest.approx(abs(im) / (2 * np.pi), rel=1e-12)
        nearest = np.min(np.abs(lam - complex(re, im)))
        assert nearest <= 1e-6 * max(1.0, abs(complex(re, im)))


def test_scene_text_and_errors():
    text = SCENE.read_text()
    a = satsim.linearize(text, base_dir=SCENES)
    np.testing.assert_array_equal(bits(a["A"]), bits(satsim.linearize(SCENE)["A"]))
    with pytest.raises(satsim.SatsimError, match="cannot read the file"):
        satsim.modes(SCENES / "missing.toml")
