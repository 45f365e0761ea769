"""satsim.fsw: the built-in flight software's blocks called from Python (contract section 16)."""

from __future__ import annotations

import numpy as np
import pytest

import satsim
import satsim.fsw
from conftest import SCENES

ARCSEC = np.pi / 180 / 3600


def test_the_mekf_in_your_own_loop_tracks_the_truth_within_its_sigma():
    """The MEKF on the flight-software example's gyro and star tracker (the built-in
    controller holding the bus while the array deploys): its attitude error against the
    truth stays within its own 3-sigma, well below the star tracker's noise about its
    boresight, and its bias estimate approaches the gyro's bias."""
    text = (SCENES / "fsw_in_the_loop.toml").read_text().replace(
        "duration = 600.0", "duration = 120.0")
    sigma_st = np.array([5.0, 5.0, 40.0]) * ARCSEC
    with satsim.Simulation(text, base_dir=SCENES) as sim:
        m = sim.measure()
        f = satsim.fsw.Mekf(noise_density=1e-5, bias_walk=1e-7, sigma_attitude=1e-3,
                            sigma_bias=1e-4, attitude=m["st"], gyro_model="sampled")
        errors, sigmas, raw = [], [], []
        while sim.t < 120.0 - 1e-9:
            m = sim.measure()
            f.update(m["st"], sigma_st)
            row = sim.row()
            truth = [row["q_w"], row["q_x"], row["q_y"], row["q_z"]]
            errors.append(satsim.fsw.attitude_error(f.attitude, truth))
            sigmas.append(f.sigma_attitude)
            raw.append(satsim.fsw.attitude_error(m["st"], truth))
            f.propagate(m["gyro"], 0.1)
            sim.advance(0.1)
    errors, sigmas, raw = np.array(errors), np.array(sigmas), np.array(raw)
    late = slice(len(errors) // 2, None)
    # Consistent: the error within 3 sigma nearly always, its spread near the sigma.
    within = np.abs(errors[late]) <= 3 * sigmas[late]
    assert within.mean() > 0.98, within.mean()
    spread = errors[late].std(axis=0) / sigmas[late].mean(axis=0)
    assert np.all((spread > 0.5) & (spread < 1.5)), spread
    # Better than the star tracker alone about its boresight (40 arcsec).
    assert errors[late, 2].std() < 0.7 * raw[late, 2].std()
    # The gyro's bias is [2e-6, -1e-6, 5e-7] rad/s (plus its walk: 1e-7 rad/s^2/sqrt(Hz)).
    assert np.all(np.abs(f.bias - [2e-6, -1e-6, 5e-7]) < 4 * f.sigma_bias + 2e-6), f.bias


def test_bad_input_is_refused_and_leaves_the_filter_as_it_was():
    f = satsim.fsw.Mekf(noise_density=1e-5, bias_walk=1e-7, sigma_attitude=0.01,
                        sigma_bias=1e-4)
    with pytest.raises(satsim.SatsimError):
        satsim.fsw.Mekf(noise_density=-1.0, bias_walk=1e-7, sigma_attitude=0.01,
                        sigma_bias=1e-4)
    before = f.covariance.copy()
    with pytest.raises(satsim.SatsimError):
        f.propagate([np.nan, 0.0, 0.0], 0.1)
    with pytest.raises(satsim.SatsimError):
        f.update([1.0, 0.0, 0.0, 0.0], -1.0)
    assert np.array_equal(f.covariance, before)
    assert f.covariance.shape == (6, 6)
    f.propagate([0.0, 0.0, 0.01], 1.0)
    # Turned by 0.01 rad about z, exactly.
    assert np.allclose(f.attitude, [np.cos(0.005), 0, 0, np.sin(0.005)], atol=1e-15)
