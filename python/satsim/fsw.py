"""The built-in flight software's blocks, callable on arrays from your own loop (contract
section 16): the same code a scene's ``[fsw]`` blocks run.

::

    import satsim.fsw

    f = satsim.fsw.Mekf(noise_density=1e-5, bias_walk=1e-7, sigma_attitude=0.01,
                        sigma_bias=1e-4, attitude=first_star_tracker_reading)
    # every gyro period T: a star tracker reading (if one was taken), then the gyro's
    f.update(m["st"], sigma=np.radians([5, 5, 40]) / 3600)
    f.propagate(m["gyro"], T)
    f.attitude, f.bias, f.sigma_attitude, f.rate(m["gyro"]), f.covariance

Conventions (satsim's): quaternions Hamilton ``[w, x, y, z]``, body to inertial, as the star
tracker reports them; rates in rad/s in the body's axes; the attitude error ``δθ`` (rad, body
axes) with ``q_true = q_est ⊗ exp(δθ/2)`` (:func:`attitude_error`).
"""

from __future__ import annotations

from typing import Sequence, Union

import numpy as np

from . import _satsim

__all__ = ["Mekf", "attitude_error"]


class Mekf:
    """The multiplicative extended Kalman filter for the attitude and the gyro bias, from a
    rate gyro and star trackers (the scene's ``[fsw.estimator] kind = "mekf"``).

    ``noise_density`` (rad/s/√Hz) and ``bias_walk`` (rad/s²/√Hz) are the gyro's, as in the
    scene's ``[[sensors.gyro]]``; ``sigma_attitude`` (rad) and ``sigma_bias`` (rad/s) the
    initial 1-sigmas; ``attitude`` and ``bias`` the initial estimate (a first star tracker
    reading is the natural start). ``gyro_model``: ``"continuous"`` (Farrenkopf's model,
    Markley & Crassidis sec. 6.2.4) or ``"sampled"`` (satsim's gyro exactly: its noise held
    over each period). Propagate once per gyro sample with ``dt`` its period. Bad input
    (a negative sigma, a non-finite reading) raises :class:`satsim.SatsimError` and leaves the
    filter as it was. The guide's estimator page has the equations.
    """

    __slots__ = ("_native",)

    def __init__(
        self,
        *,
        noise_density: float,
        bias_walk: float,
        sigma_attitude: float,
        sigma_bias: float,
        attitude: Sequence[float] = (1.0, 0.0, 0.0, 0.0),
        bias: Sequence[float] = (0.0, 0.0, 0.0),
        gyro_model: str = "continuous",
    ) -> None:
        if gyro_model not in ("continuous", "sampled"):
            raise _satsim.SatsimError(
                f"gyro_model must be 'continuous' or 'sampled', got {gyro_model!r}")
        self._native = _satsim.NativeMekf(
            float(noise_density), float(bias_walk), float(sigma_attitude), float(sigma_bias),
            [float(x) for x in attitude], [float(x) for x in bias], gyro_model == "sampled")

    def propagate(self, omega: Sequence[float], dt: float) -> None:
        """Propagates over ``dt`` (s) with the gyro reading ``omega`` (rad/s) held."""
        self._native.propagate([float(x) for x in omega], float(dt))

    def update(self, q: Sequence[float], sigma: Union[float, Sequence[float]]) -> None:
        """A star tracker reading ``q`` ``[w, x, y, z]`` with its 1-sigma ``sigma`` (rad,
        about the body's x, y, z axes; one number for all three)."""
        s = [float(sigma)] * 3 if np.ndim(sigma) == 0 else [float(x) for x in sigma]
        self._native.update_attitude([float(x) for x in q], s)

    update_attitude = update

    @property
    def attitude(self) -> np.ndarray:
        """The attitude estimate ``[w, x, y, z]`` (``w >= 0``)."""
        return np.array(self._native.attitude)

    @property
    def bias(self) -> np.ndarray:
        """The gyro bias estimate (rad/s)."""
        return np.array(self._native.bias)

    @property
    def sigma_attitude(self) -> np.ndarray:
        """The attitude's 1-sigma about the body's axes (rad)."""
        return np.array(self._native.sigma_attitude)

    @property
    def sigma_bias(self) -> np.ndarray:
        """The bias's 1-sigma (rad/s)."""
        return np.array(self._native.sigma_bias)

    @property
    def covariance(self) -> np.ndarray:
        """The 6 × 6 covariance of ``[attitude error (rad); bias error (rad/s)]``."""
        return self._native.covariance

    def rate(self, omega: Sequence[float]) -> np.ndarray:
        """The rate estimate: the gyro reading less the bias estimate (rad/s)."""
        return np.array(self._native.rate([float(x) for x in omega]))

    def __repr__(self) -> str:
        return f"satsim.fsw.Mekf(attitude={self.attitude.tolist()}, bias={self.bias.tolist()})"


def attitude_error(q_est: Sequence[float], q_true: Sequence[float]) -> np.ndarray:
    """The rotation vector ``δθ`` (rad, the estimate's body axes) with
    ``q_true = q_est ⊗ exp(δθ/2)``: its norm is the estimate's error angle."""
    return np.array(_satsim.attitude_error([float(x) for x in q_est], [float(x) for x in q_true]))
