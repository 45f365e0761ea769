"""satsim.fsw: the built-in flight software's blocks called from Python (contract section 16)."""

from __future__ import annotations

import warnings

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


# --- The other blocks: TRIAD, vector updates, guidance, slew, PID, magnetic laws. -----------
# Independent numpy helpers: Hamilton quaternions [w, x, y, z], body to inertial.

def _qmat(q):
    """The rotation matrix (body to inertial) of the quaternion q."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def _qmul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
    ])


def _axis_angle(axis, angle):
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * a])


def _random_q(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    return q * np.sign(q[0])


def _angle(qa, qb):
    """The angle (rad) between two attitudes."""
    d = abs(float(np.dot(qa, qb)) / (np.linalg.norm(qa) * np.linalg.norm(qb)))
    return 2 * np.arccos(min(1.0, d))


def test_triad_is_exact_without_noise_and_its_covariance_is_shuster_oh():
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = _random_q(rng)
        r1, r2 = rng.normal(size=3) * 1e11, rng.normal(size=3) * 3e-5   # a Sun, a field
        m = _qmat(q)
        b1, b2 = m.T @ r1, m.T @ r2
        est = satsim.fsw.triad(b1, b2, r1, r2)
        assert est[0] >= 0 and abs(np.linalg.norm(est) - 1) < 1e-14
        assert np.allclose(est, q, atol=1e-12), (est, q)
        assert np.allclose(_qmat(est), m, atol=1e-12)
    # The primary is mapped exactly even with a noisy secondary.
    q = _random_q(rng)
    r1, r2 = np.array([1.0, 0.2, -0.1]), np.array([-0.3, 1.0, 0.5])
    b1, b2 = _qmat(q).T @ r1, _qmat(q).T @ r2 + [0.01, 0.0, 0.0]
    est = satsim.fsw.triad(b1, b2, r1, r2)
    assert np.allclose(_qmat(est) @ (b1 / np.linalg.norm(b1)), r1 / np.linalg.norm(r1),
                       atol=1e-14)
    # Covariance, orthogonal pair: sigma2 about the primary, sigma1 across it.
    p = satsim.fsw.triad_covariance([2.0, 0, 0], [0, 5.0, 0], 1e-3, 3e-3)
    assert p.shape == (3, 3)
    assert np.allclose(p, np.diag([9e-6, 1e-6, 1e-6]), rtol=0, atol=1e-20)
    # A general pair against the formula, written out here.
    u1, u2 = np.array([1.0, 0.0, 0.0]), np.array([np.cos(1.0), np.sin(1.0), 0.0])
    s1, s2 = 2e-3, 5e-3
    want = s1 ** 2 * np.eye(3) + ((s2 ** 2 - s1 ** 2) * np.outer(u1, u1) + s1 ** 2 * np.cos(
        1.0) * (np.outer(u1, u2) + np.outer(u2, u1))) / np.sin(1.0) ** 2
    got = satsim.fsw.triad_covariance(u1 * 3, u2 * 0.5, s1, s2)
    assert np.allclose(got, want, rtol=1e-12, atol=0)
    assert np.array_equal(got, got.T)
    # Bad input: a ValueError with the Rust message.
    with pytest.raises(ValueError, match="parallel"):
        satsim.fsw.triad([1, 0, 0], [2, 0, 0], [1, 0, 0], [0, 1, 0])
    with pytest.raises(ValueError, match="non-zero"):
        satsim.fsw.triad([1, 0, 0], [0, 1, 0], [0, 0, 0], [0, 1, 0])
    with pytest.raises(ValueError):
        satsim.fsw.triad_covariance([1, 0, 0], [1, 1e-9, 0], 1e-3, 1e-3)


def test_update_vector_corrects_across_the_direction_only():
    s0, s_meas = 0.01, 1e-3
    kw = dict(noise_density=1e-5, bias_walk=1e-7, sigma_attitude=s0, sigma_bias=1e-4)
    r = np.array([0.0, 0.0, 1.0])              # the reference direction: inertial z
    # The truth turned 5 mrad about x from the estimate (identity): z seen turned.
    q_true = _axis_angle([1, 0, 0], 5e-3)
    f = satsim.fsw.Mekf(**kw)
    before = satsim.fsw.attitude_error(f.attitude, q_true)
    assert np.allclose(before, [5e-3, 0, 0], atol=1e-15)
    f.update_vector(_qmat(q_true).T @ r * 4.2, r * 1e-5, s_meas)   # any lengths
    after = satsim.fsw.attitude_error(f.attitude, q_true)
    # The scalar Kalman gain across z: the error falls to s_meas²/(s0² + s_meas²) of itself.
    k = s0 ** 2 / (s0 ** 2 + s_meas ** 2)
    assert np.linalg.norm(after) < 0.02 * np.linalg.norm(before)
    assert abs(after[0] - (1 - k) * 5e-3) < 1e-7, after
    # Sigma shrinks across the direction (x, y) to (1/s0² + 1/s_meas²)^-1/2, not along it (z).
    post = (1 / s0 ** 2 + 1 / s_meas ** 2) ** -0.5
    sig = f.sigma_attitude
    assert np.allclose(sig[:2], post, rtol=1e-9), sig
    assert sig[2] == pytest.approx(s0, rel=1e-12)
    # A rotation about the direction itself is not seen: nothing moves.
    g = satsim.fsw.Mekf(**kw)
    q_z = _axis_angle([0, 0, 1], 0.3)
    g.update_vector(_qmat(q_z).T @ r, r, s_meas)
    assert np.allclose(g.attitude, [1, 0, 0, 0], atol=1e-15)
    # A zero vector (a Sun sensor in umbra) is refused, the filter as it was.
    p = g.covariance.copy()
    with pytest.raises(ValueError, match="non-zero"):
        g.update_vector([0, 0, 0], r, s_meas)
    for bad in (-1e-3, np.nan, np.inf):
        with pytest.raises(ValueError, match="sigma must be a finite number >= 0"):
            g.update_vector(r, r, bad)
    assert np.array_equal(g.covariance, p)


def _symmetric_positive_definite(c):
    assert np.all(np.isfinite(c)), c
    assert np.array_equal(c, c.T), c
    np.linalg.cholesky(c)              # raises LinAlgError unless positive definite
    assert np.min(np.linalg.eigvalsh(c)) > 0, np.linalg.eigvalsh(c)


def test_the_mekf_floors_its_update_sigmas_as_the_scene_estimator_does():
    """A sigma below MIN_SIGMA (1e-6 rad), zero included, is taken as MIN_SIGMA by the star
    tracker's and the direction updates, as a scene's estimator takes a noiseless sensor's:
    the same filter to the bit as at MIN_SIGMA, its covariance symmetric positive definite and
    finite after every update. A negative or non-finite sigma is refused."""
    assert satsim.fsw.MIN_SIGMA == 1e-6
    q_true = _axis_angle([1, 2, 3], 0.3)
    sun, field = np.array([0.3, 0.9, 0.1]), np.array([2e-5, -1e-5, 3e-5])
    # A noiseless gyro (Q = 0): nothing regrows the covariance between the updates. The
    # filter starts 5 mrad off the truth (its 1-sigma 10 mrad).
    kw = dict(noise_density=0.0, bias_walk=0.0, sigma_attitude=0.01, sigma_bias=1e-4,
              gyro_model="sampled", attitude=_qmul(q_true, _axis_angle([1, -1, 2], 5e-3)))

    def star_tracker(sigma):
        f = satsim.fsw.Mekf(**kw)
        for _ in range(20):
            f.update(q_true, sigma)
            _symmetric_positive_definite(f.covariance)
            f.propagate([0.0, 0.0, 0.0], 0.1)
        return f

    def directions(sigma):
        f = satsim.fsw.Mekf(**kw)
        for _ in range(20):
            for r in (sun, field):
                f.update_vector(_qmat(q_true).T @ r, r, sigma)
                _symmetric_positive_definite(f.covariance)
            f.propagate([0.0, 0.0, 0.0], 0.1)
        return f

    for run, tiny in ((star_tracker, (0.0, 1e-12, [0.0, 1e-9, 1e-300])),
                      (directions, (0.0, 1e-12, 1e-300))):
        floor = run(1e-6)
        assert np.all(floor.sigma_attitude < 1e-6), floor.sigma_attitude
        # The exact readings bring it within the filter's own 3-sigma.
        error = satsim.fsw.attitude_error(floor.attitude, q_true)
        assert np.all(np.abs(error) < 3 * floor.sigma_attitude), (error, floor.sigma_attitude)
        for s in tiny:
            f = run(s)
            assert np.array_equal(f.covariance, floor.covariance), (run.__name__, s)
            assert np.array_equal(f.attitude, floor.attitude), (run.__name__, s)
        # Above the floor a sigma is its own.
        assert not np.array_equal(run(2e-6).covariance, floor.covariance)
    # Refused, the filter as it was: the floor does not hide a negative or NaN sigma.
    f = star_tracker(1e-6)
    p = f.covariance.copy()
    for bad in (-1e-3, np.nan, [1e-6, -1e-9, 1e-6]):
        with pytest.raises(satsim.SatsimError, match="sigma must be finite numbers >= 0"):
            f.update(q_true, bad)
        with pytest.raises(satsim.SatsimError, match="sigma must be a finite number >= 0"):
            f.update_vector(sun, sun, -1e-3 if np.ndim(bad) else bad)
    assert np.array_equal(f.covariance, p)
    # from_triad floors TRIAD's sigmas too, as the sun_mag estimator's start does.
    b1, b2 = _qmat(q_true).T @ sun, _qmat(q_true).T @ field
    tri = dict(noise_density=0.0, bias_walk=0.0, sigma_bias=1e-4)
    g = satsim.fsw.Mekf.from_triad(b1, b2, sun, field, 0.0, 0.0, **tri)
    assert np.array_equal(g.covariance[:3, :3],
                          satsim.fsw.triad_covariance(b1, b2, 1e-6, 1e-6))
    _symmetric_positive_definite(g.covariance)
    with pytest.raises(satsim.SatsimError, match="sigma2 must be a finite number >= 0"):
        satsim.fsw.Mekf.from_triad(b1, b2, sun, field, 1e-3, -1e-3, **tri)


def test_mekf_from_triad_starts_as_the_sun_mag_estimator():
    rng = np.random.default_rng(3)
    q = _random_q(rng)
    sun, field = np.array([0.3, 0.9, 0.1]), np.array([2e-5, -1e-5, 3e-5])
    b1, b2 = _qmat(q).T @ sun, _qmat(q).T @ field
    f = satsim.fsw.Mekf.from_triad(b1, b2, sun, field, 1e-3, 2e-2, noise_density=1e-5,
                                   bias_walk=1e-7, sigma_bias=1e-4, gyro_model="sampled")
    assert np.allclose(f.attitude, q, atol=1e-12)
    c = f.covariance
    assert np.allclose(c[:3, :3], satsim.fsw.triad_covariance(b1, b2, 1e-3, 2e-2), rtol=1e-12)
    assert np.array_equal(c[:3, 3:], np.zeros((3, 3)))
    assert np.allclose(np.diag(c[3:, 3:]), 1e-8, rtol=1e-12)
    # It then runs as any filter: the Sun's direction again tightens the attitude across it.
    before = f.sigma_attitude.copy()
    f.update_vector(b1, sun, 1e-3)
    assert np.all(f.sigma_attitude <= before * (1 + 1e-12))
    with pytest.raises(ValueError, match="positive definite"):
        f.set_attitude_covariance(-np.eye(3))


def _lvlh(r, v):
    z = -r / np.linalg.norm(r)
    h = np.cross(r, v)
    y = -h / np.linalg.norm(h)
    x = np.cross(y, z)
    return np.column_stack([x, y, z])


def test_nadir_guidance_is_the_lvlh_frame():
    rng = np.random.default_rng(11)
    law = satsim.fsw.Guidance.nadir()
    assert law.needs_orbit and law.kind == "nadir"
    for _ in range(10):
        r = rng.normal(size=3) * 7e6
        v = rng.normal(size=3) * 7.5e3
        ref = law.reference(12.0, r, v)
        m = _lvlh(r, v)
        assert np.allclose(_qmat(ref.attitude), m, atol=1e-12, rtol=0)
        # The frame's rate r × v / r² in its own axes.
        w = m.T @ np.cross(r, v) / np.dot(r, r)
        assert np.allclose(ref.rate, w, rtol=0, atol=1e-12 * np.linalg.norm(w))
        # dω/dt = −2 ω (r·v)/r² (two-body: h constant).
        wd = -2 * w * np.dot(r, v) / np.dot(r, r)
        assert np.allclose(ref.acceleration, wd, rtol=0, atol=1e-12 * np.linalg.norm(wd))
        # An offset: the LVLH frame times it.
        off = _random_q(rng)
        ro = satsim.fsw.Guidance.nadir(off).reference(0.0, r, v)
        assert np.allclose(_qmat(ro.attitude), m @ _qmat(off), atol=1e-12, rtol=0)
    # A circular equatorial orbit: (0, −n, 0), no acceleration; dict access and unpacking.
    r, v = [7e6, 0, 0], [0, 7.5e3, 0]
    att, rate, acc = law.reference(0.0, r, v)
    assert np.allclose(rate, [0, -7.5e3 / 7e6, 0], rtol=1e-14, atol=0)
    assert np.array_equal(acc, np.zeros(3))
    assert np.array_equal(law.reference(0.0, r, v)["attitude"], att)
    with pytest.raises(ValueError, match="orbit"):
        law.reference(0.0)
    with pytest.raises(ValueError):
        law.reference(0.0, r=r)
    # Inertial: fixed, no orbit.
    q = _random_q(rng)
    ri = satsim.fsw.Guidance.inertial(q).reference(100.0)
    assert np.allclose(ri.attitude, q, atol=1e-15)
    # Three times unit norm is refused, as a scene refuses it.
    with pytest.raises(satsim.SatsimError, match="within 1e-3"):
        satsim.fsw.Guidance.inertial(q * 3.0)
    assert np.array_equal(ri.rate, np.zeros(3)) and np.array_equal(ri.acceleration, np.zeros(3))


def _sun_gcrf_low_precision(epoch_days_j2000):
    """The geocentric Sun (m, J2000 equatorial axes) by the Astronomical Almanac's
    low-precision formulae (0.01°; satsim's Sun is within 0.002° of it), the ecliptic
    longitude taken back to J2000 by the general precession (1.3969° per century)."""
    n = epoch_days_j2000
    g = np.radians(357.528 + 0.9856003 * n)
    lam = 280.460 + 0.9856474 * n + 1.915 * np.sin(g) + 0.020 * np.sin(2 * g)
    lam = np.radians(lam - 1.3969 * n / 36525)
    eps = np.radians(23.4393)
    dist = (1.00014 - 0.01671 * np.cos(g) - 0.00014 * np.cos(2 * g)) * 1.495978707e11
    return dist * np.array([np.cos(lam), np.cos(eps) * np.sin(lam), np.sin(eps) * np.sin(lam)])


def test_sun_guidance_puts_the_axis_on_the_sun_whatever_the_secondary():
    import datetime
    epoch = "2026-03-20T12:00:00 UTC"
    r = np.array([5e6, -4e6, 2.5e6])
    v = np.array([3e3, 4.5e3, 4e3])
    axis = np.array([1.0, 1.0, 0.0])
    a = axis / np.linalg.norm(axis)
    t = 5000.0
    pointed = []
    for secondary in ([0, 0, 1], [0.2, -0.1, 1.0], [1, -1, 0.3]):
        law = satsim.fsw.Guidance.sun(axis * 3, secondary, epoch)
        ref = law.reference(t, r, v)
        m = _qmat(ref.attitude)
        p = m @ a
        pointed.append(p)
        # The secondary lies in the plane of the Sun line and the orbit normal.
        n = np.cross(r, v) / np.linalg.norm(np.cross(r, v))
        s2 = m @ (np.array(secondary) / np.linalg.norm(secondary))
        assert abs(np.dot(s2, np.cross(p, n))) < 1e-12
    for p in pointed:
        assert abs(np.linalg.norm(p) - 1) < 1e-14
        assert np.allclose(p, pointed[0], atol=1e-12)
    # Where the Sun is, by an independent low-precision ephemeris.
    days = (datetime.datetime(2026, 3, 20, 12) - datetime.datetime(2000, 1, 1, 12)
            ).total_seconds() / 86400 + t / 86400
    s = _sun_gcrf_low_precision(days) - r
    s /= np.linalg.norm(s)
    assert np.degrees(np.arccos(np.clip(np.dot(pointed[0], s), -1, 1))) < 0.01
    # A day later, the Sun has moved about a degree: the law follows it.
    later = satsim.fsw.Guidance.sun(axis, [0, 0, 1], epoch).reference(t + 86400.0, r, v)
    d = np.degrees(np.arccos(np.dot(_qmat(later.attitude) @ a, pointed[0])))
    assert 0.8 < d < 1.2, d
    # Bad input: parallel axes, a bad epoch, no orbit.
    with pytest.raises(ValueError):
        satsim.fsw.Guidance.sun([1, 0, 0], [-2, 0, 0], epoch)
    with pytest.raises(ValueError, match="epoch"):
        satsim.fsw.Guidance.sun([1, 0, 0], [0, 0, 1], "2026-13-40")
    with pytest.raises(ValueError):
        satsim.fsw.Guidance.sun([1, 0, 0], [0, 0, 1], epoch).reference(t)


def test_target_guidance_points_the_axis_at_a_point_on_the_ground():
    """Seen from far (4e7 m), the point's place by a simple Earth rotation (GMST, no
    precession: 0.36° off in 2026, 40 km on the ground; found 0.05° off) is within 0.2° of
    where the law points; an hour's rotation of the Earth (15°) would be far outside it."""
    import datetime
    epoch = "2026-03-20T12:00:00 UTC"
    lat, lon, alt = 48.85, 2.35, 35.0
    law = satsim.fsw.Guidance.target(lat, lon, alt, epoch=epoch)
    assert law.kind == "target"
    t = 3600.0
    # The point, Earth-fixed (WGS-84), then turned by GMST.
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    phi, lam = np.radians(lat), np.radians(lon)
    nn = a / np.sqrt(1 - e2 * np.sin(phi) ** 2)
    p_itrf = np.array([(nn + alt) * np.cos(phi) * np.cos(lam),
                       (nn + alt) * np.cos(phi) * np.sin(lam),
                       (nn * (1 - e2) + alt) * np.sin(phi)])
    days = (datetime.datetime(2026, 3, 20, 12) - datetime.datetime(2000, 1, 1, 12)
            ).total_seconds() / 86400 + t / 86400
    gmst = np.radians((280.46061837 + 360.98564736629 * days) % 360)
    c, s_ = np.cos(gmst), np.sin(gmst)
    p = np.array([[c, -s_, 0], [s_, c, 0], [0, 0, 1]]) @ p_itrf
    u = p / np.linalg.norm(p)
    side = np.cross(u, [0, 0, 1])
    r = 4.2e7 * (u + 0.3 * side / np.linalg.norm(side))
    v = np.cross([0, 0, 1], r) / np.linalg.norm(r) * 3.07e3 + [0, 0, 100.0]
    ref = law.reference(t, r, v)
    assert abs(np.linalg.norm(ref.attitude) - 1) < 1e-14
    assert np.all(np.isfinite(ref.rate)) and np.all(np.isfinite(ref.acceleration))
    z = _qmat(ref.attitude)[:, 2]                  # the default axis: body +z
    d = (p - r) / np.linalg.norm(p - r)
    assert np.degrees(np.arccos(np.clip(np.dot(z, d), -1, 1))) < 0.2
    with pytest.raises(ValueError, match="latitude"):
        satsim.fsw.Guidance.target(91.0, 0.0, 0.0, epoch=epoch)


def test_slew_never_exceeds_its_rate_and_acceleration_in_a_90_degree_step():
    max_rate, max_acc, dt = 0.02, 1e-3, 0.1
    slew = satsim.fsw.Slew(max_rate, max_acc)
    q0 = np.array([1.0, 0.0, 0.0, 0.0])
    target = satsim.fsw.Guidance.inertial(_axis_angle([1, 2, -1], np.pi / 2)).reference(0.0)
    slew.reset(q0, [0, 0, 0])
    first = slew.step(target, dt)
    assert np.allclose(first.attitude, q0, atol=1e-15)
    prev_q, prev_w = first.attitude, first.rate
    turned = 0.0
    for k in range(2000):
        ref = slew.step(target, dt)
        w = np.linalg.norm(ref.rate)
        assert w <= max_rate * (1 + 1e-12), (k, w)
        assert np.linalg.norm(ref.rate - prev_w) <= max_acc * dt * (1 + 1e-9)
        # The attitudes themselves (not only the reported rate) turn within the limit.
        step_angle = _angle(prev_q, ref.attitude)
        assert step_angle <= max_rate * dt * (1 + 1e-9) + 1e-12
        turned += step_angle
        prev_q, prev_w = ref.attitude, ref.rate
    assert _angle(prev_q, target.attitude) < 1e-9
    assert slew.remaining_angle < 1e-9
    assert turned == pytest.approx(np.pi / 2, rel=1e-6)   # an eigenaxis slew, no detour
    # It took at least the rate-limited time.
    with pytest.raises(ValueError, match="max_rate"):
        satsim.fsw.Slew(0.0, 1e-3)


def test_pid_pushes_back_against_the_error_and_the_wheels_take_minus_u():
    kp, ki, kd = np.array([1.0, 2.0, 3.0]), 0.1, 10.0
    pid = satsim.fsw.Pid(kp, ki, kd)
    q_ref = np.array([1.0, 0.0, 0.0, 0.0])
    # The estimate turned +0.1 rad about x from the reference, and turning about y.
    q_est = _axis_angle([1, 0, 0], 0.1)
    u = pid.torque(q_est, [0, 0.01, 0], q_ref, [0, 0, 0], 0.5)
    assert np.allclose(pid.integral, [0.05, 0, 0], atol=1e-15)
    assert np.allclose(u, [-1.0 * 0.1 - 0.1 * 0.05, -10.0 * 0.01, 0.0], atol=1e-14), u
    # The reference rate counts in the estimate's axes: matching rates leave no D term.
    pid.reset()
    assert np.array_equal(pid.integral, np.zeros(3))
    u2 = pid.torque(q_ref, [0, 0, 0.02], q_ref, [0, 0, 0.02], 0.5)
    assert np.allclose(u2, 0, atol=1e-18)
    # Orthogonal wheels: the commands are −u (the wheels apply −Σ τ_j a_j).
    pid.allocate(np.eye(3), 1.0)
    assert pid.n_wheels == 3 and np.allclose(pid.capability, 1.0)
    assert np.allclose(pid.commands(u), -u, atol=1e-15)
    # The body gets u from any wheel set that spans it: −A τ = u.
    axes = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]]) / np.array(
        [[1], [1], [1], [np.sqrt(3)]])
    pid.allocate(axes, [1.0] * 4)
    tau = pid.commands(u)
    assert tau.shape == (4,)
    assert np.allclose(-(axes.T @ tau), u, atol=1e-14)
    # Over the limit: scaled down as a whole, keeping the direction.
    pid.allocate(np.eye(3), 0.01)
    tau = pid.commands(u)
    assert np.max(np.abs(tau)) == pytest.approx(0.01, rel=1e-12)
    assert np.allclose(tau / np.linalg.norm(tau), -u / np.linalg.norm(u), atol=1e-12)
    # Inertia feed-forward ω × (J ω).
    j = np.diag([10.0, 20.0, 30.0])
    w = np.array([0.01, -0.02, 0.03])
    pj = satsim.fsw.Pid(0.0, 0.0, 0.0, inertia=j)
    assert np.allclose(pj.torque(q_ref, w, q_ref, w, 0.1), np.cross(w, j @ w), atol=1e-18)
    with pytest.raises(ValueError, match="max_torque"):
        pid.allocate(np.eye(3), [1.0, 1.0])
    with pytest.raises(ValueError, match="kp"):
        satsim.fsw.Pid(-1.0, 0.0, 0.0)


def test_magnetic_laws_oppose_the_rate_and_the_momentum():
    rng = np.random.default_rng(5)
    k, dt = 1e4, 0.1
    for _ in range(10):
        b = rng.normal(size=3) * 3e-5
        w = rng.normal(size=3) * 0.05
        # Body-frame field of a body spinning at w: db/dt = −w × b.
        b_next = b - dt * np.cross(w, b)
        m = satsim.fsw.bdot_dipole(k, b, b_next, dt)
        assert np.allclose(m, -k * (b_next - b) / dt, rtol=1e-14, atol=0)
        assert np.dot(np.cross(m, b_next), w) < 0          # the torque slows the spin
        h = rng.normal(size=3) * 0.1
        md = satsim.fsw.momentum_dipole(0.01, h, b)
        tau = np.cross(md, b)
        h_perp = h - b * np.dot(h, b) / np.dot(b, b)
        assert np.allclose(tau, -0.01 * h_perp, rtol=1e-12, atol=1e-18)  # dumps h across b
    assert np.array_equal(satsim.fsw.momentum_dipole(1.0, [1, 2, 3], [0, 0, 0]), np.zeros(3))
    assert np.allclose(satsim.fsw.gyro_mean([0, 1, 2], [2, 3, 4]), [1, 2, 3])
    with pytest.raises(ValueError, match="dt"):
        satsim.fsw.bdot_dipole(k, [0, 0, 0], [1, 0, 0], 0.0)


def test_guidance_quaternions_follow_the_scene_rule():
    # Within 1e-3 of unit norm: normalised, a UserWarning when more than rounding off.
    with pytest.warns(UserWarning, match="normalised"):
        g = satsim.fsw.Guidance.inertial([0.70711, 0.0, 0.0, 0.70711])
    q = np.asarray(g.reference(0.0).attitude)
    assert abs(np.linalg.norm(q) - 1.0) < 1e-15
    assert abs(q[0] - q[3]) < 1e-15
    with pytest.warns(UserWarning, match="normalised"):
        satsim.fsw.Guidance.nadir([1.0, 0.01, 0.0, 0.0])
    # Beyond: refused, the tolerance stated.
    for bad in ([2.0, 0.0, 0.0, 0.0], [1.0, 0.1, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]):
        with pytest.raises(satsim.SatsimError, match="within 1e-3"):
            satsim.fsw.Guidance.inertial(bad)
    with pytest.raises(satsim.SatsimError, match="within 1e-3"):
        satsim.fsw.Guidance.nadir([2.0, 0.0, 0.0, 0.0])


def test_the_slew_and_the_pid_take_quaternions_by_the_scene_rule():
    """Slew and Pid follow Guidance's (a scene's) rule: beyond 1e-3 of unit norm a quaternion
    is refused, naming the argument, before anything moves; within it, normalised with a
    UserWarning. A star tracker's reading is any non-zero norm, as the scene's estimator's."""
    zero = [0.0, 0.0, 0.0]
    q_est, q_ref = _axis_angle([1, 0, 0], 0.1), _axis_angle([0, 1, 1], 0.2)
    for bad in ([2.0, 0.0, 0.0, 0.0], [0.1, 0.0, 0.0, 0.0], [1.0, 0.1, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0]):
        pid = satsim.fsw.Pid(1.0, 0.1, 1.0)
        with pytest.raises(satsim.SatsimError, match=r"^q_est: .*within 1e-3"):
            pid.torque(bad, zero, q_ref, zero, 0.5)
        with pytest.raises(satsim.SatsimError, match=r"^q_ref: .*within 1e-3"):
            pid.torque(q_est, zero, bad, zero, 0.5)
        assert np.array_equal(pid.integral, np.zeros(3))      # the refusals integrated nothing
        slew = satsim.fsw.Slew(0.02, 1e-3)
        with pytest.raises(satsim.SatsimError, match=r"^attitude: .*within 1e-3"):
            slew.reset(bad)
        for target in (bad, satsim.fsw.Reference(bad), {"attitude": bad}):
            with pytest.raises(satsim.SatsimError, match=r"^the reference's attitude: .*1e-3"):
                slew.step(target, 0.1)
        assert slew.remaining_angle is None                    # nothing stepped
    with pytest.raises(satsim.SatsimError, match="q_est must be finite"):
        satsim.fsw.Pid(1.0, 0.0, 1.0).torque([np.nan, 0, 0, 1], zero, q_ref, zero, 0.1)
    # Within 1e-3: normalised, with a warning; the torque is the unit quaternions'.
    pid, unit = satsim.fsw.Pid(1.0, 0.1, 1.0), satsim.fsw.Pid(1.0, 0.1, 1.0)
    with pytest.warns(UserWarning, match="q_est: quaternion norm 1.0005 is not 1; normalised"):
        u = pid.torque(q_est * 1.0005, [0.0, 0.01, 0.0], q_ref, zero, 0.5)
    assert np.allclose(u, unit.torque(q_est, [0.0, 0.01, 0.0], q_ref, zero, 0.5),
                       rtol=1e-15, atol=0)
    with pytest.warns(UserWarning, match="q_ref: quaternion norm 0.9995 is not 1"):
        pid.torque(q_est, zero, q_ref * 0.9995, zero, 0.5)
    slew = satsim.fsw.Slew(0.02, 1e-3)
    with pytest.warns(UserWarning, match="attitude: quaternion norm"):
        slew.reset(q_est * 1.0005)
    with pytest.warns(UserWarning, match="the reference's attitude: quaternion norm"):
        ref = slew.step(q_ref * 1.0005, 0.1)
    assert np.allclose(ref.attitude, q_est, rtol=0, atol=1e-15)   # reset: not advanced
    # Unit to rounding: silent.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pid.torque(q_est, zero, q_ref, zero, 0.5)
        slew.step(q_ref, 0.1)
    # A star tracker's reading may be quantised: any non-zero norm, as the scene's estimator.
    kw = dict(noise_density=1e-5, bias_walk=1e-7, sigma_attitude=0.01, sigma_bias=1e-4)
    f, g = satsim.fsw.Mekf(**kw), satsim.fsw.Mekf(**kw)
    f.update(q_est * 1.01, 1e-3)
    g.update(q_est, 1e-3)
    assert np.allclose(f.attitude, g.attitude, rtol=0, atol=1e-15)
    assert np.allclose(satsim.fsw.attitude_error(q_est * 1.01, q_ref),
                       satsim.fsw.attitude_error(q_est, q_ref), rtol=0, atol=1e-15)
    with pytest.raises(satsim.SatsimError, match="non-zero"):
        f.update([0.0, 0.0, 0.0, 0.0], 1e-3)
    # attitude_error gave NaN for a zero quaternion: refused, naming it.
    with pytest.raises(satsim.SatsimError, match="q_true must be a non-zero quaternion"):
        satsim.fsw.attitude_error(q_est, [0.0, 0.0, 0.0, 0.0])


def test_degenerate_and_non_finite_input_is_refused_as_a_scene_refuses_it():
    law = satsim.fsw.Guidance.nadir()
    v = [0.0, 7.6e3, 0.0]
    with pytest.raises(satsim.SatsimError, match="r is zero"):
        law.reference(0.0, r=[0.0, 0.0, 0.0], v=v)
    with pytest.raises(satsim.SatsimError, match="parallel to r"):
        law.reference(0.0, r=[7e6, 0.0, 0.0], v=[7.6e3, 0.0, 0.0])
    att = law.reference(0.0, r=[7e6, 0.0, 0.0], v=v).attitude
    assert np.all(np.isfinite(att))
    with pytest.raises(satsim.SatsimError, match="finite"):
        satsim.fsw.gyro_mean([float("nan"), 0.0, 0.0], [0.0, 0.0, 0.0])
    f = satsim.fsw.Mekf(noise_density=1e-5, bias_walk=1e-7, sigma_attitude=0.01,
                        sigma_bias=1e-4, attitude=[1.0, 0.0, 0.0, 0.0], bias=[0.0, 0.0, 0.0])
    with pytest.raises(satsim.SatsimError, match="non-finite"):
        f.propagate([1e200, 0.0, 0.0], 0.1)
    assert np.all(np.isfinite(f.attitude)) and np.all(np.isfinite(f.covariance))
    for gain in (-1.0, 0.0):
        with pytest.raises(satsim.SatsimError, match="> 0"):
            satsim.fsw.bdot_dipole(gain, [1e-5, 0.0, 0.0], [2e-5, 0.0, 0.0], 1.0)
        with pytest.raises(satsim.SatsimError, match="> 0"):
            satsim.fsw.momentum_dipole(gain, [0.1, 0.0, 0.0], [0.0, 3e-5, 0.0])
    with pytest.raises(satsim.SatsimError, match="positive definite"):
        satsim.fsw.Pid(1.0, 0.0, 1.0, inertia=-np.diag([20.0, 25.0, 30.0]))
