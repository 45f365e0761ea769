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

The guidance, the slew shaper and the control law are there too, so a whole pointing loop
runs in Python on satsim's blocks::

    law = satsim.fsw.Guidance.nadir()
    slew = satsim.fsw.Slew(max_rate=0.02, max_acceleration=1e-3)
    pid = satsim.fsw.Pid(kp=0.5, ki=0.0, kd=5.0)
    pid.allocate(wheel_axes, max_torque=[0.01] * len(wheel_axes))
    ref = slew.step(law.reference(t, r, v), dt)
    u = pid.torque(f.attitude, f.rate(m["gyro"]), ref.attitude, ref.rate, dt)
    wheel_commands = pid.commands(u)

Conventions (satsim's): quaternions Hamilton ``[w, x, y, z]``, body to inertial, as the star
tracker reports them; rates in rad/s in the body's axes; the attitude error ``δθ`` (rad, body
axes) with ``q_true = q_est ⊗ exp(δθ/2)`` (:func:`attitude_error`). Inertial is the GCRF
(Earth-centred; m, m/s). Vectors and quaternions may be lists, tuples or numpy arrays; results
are numpy arrays. Bad input raises :class:`satsim.SatsimError` (a :class:`ValueError`) with
the Rust message.

A quaternion given to the guidance, the slew shaper or the control law (an attitude, a
reference, an estimate) follows a scene's rule: within 1e-3 of unit norm it is normalised,
with a :class:`UserWarning` when off by more than rounding; beyond, it is refused with a
:class:`satsim.SatsimError` naming the argument. A star tracker's reading (:meth:`Mekf.update`,
the filter's starting ``attitude``) is normalised whatever its norm, as a scene's estimator
takes a quantised reading; only a zero or non-finite one is refused.
"""

from __future__ import annotations

import math
from typing import Optional, Sequence, Union

import numpy as np

from . import _satsim

__all__ = [
    "Guidance",
    "Mekf",
    "Pid",
    "Reference",
    "Slew",
    "attitude_error",
    "bdot_dipole",
    "gyro_mean",
    "momentum_dipole",
    "triad",
    "triad_covariance",
]

#: The Earth's gravitational parameter (m³/s²), the default ``mu`` of :meth:`Guidance.reference`.
MU_EARTH = 3.986004418e14

#: The least 1-sigma (rad, about 0.2 arcsecond) the filter's updates take: a smaller one,
#: zero included, is raised to it, as a scene's estimator raises a noiseless sensor's, so
#: that the update stays well posed (a sigma near zero makes the innovation covariance
#: singular once the updates have shrunk the covariance).
MIN_SIGMA: float = _satsim.MIN_SIGMA


def _vec(x: Sequence[float], n: int = 3, name: str = "vector") -> list:
    """``x`` as a list of ``n`` floats, or :class:`satsim.SatsimError`."""
    a = np.asarray(x, dtype=float).reshape(-1)
    if a.shape != (n,):
        raise _satsim.SatsimError(f"{name} must have {n} numbers, not {np.shape(x)}")
    return a.tolist()


def _floored_sigma(sigma: float, name: str) -> float:
    """``sigma`` raised to :data:`MIN_SIGMA`, or :class:`satsim.SatsimError` unless finite and
    >= 0 (checked first: the floor would hide a negative one)."""
    s = float(sigma)
    if not (math.isfinite(s) and s >= 0.0):
        raise _satsim.SatsimError(f"{name} must be a finite number >= 0 (rad), not {s}")
    return max(s, MIN_SIGMA)


def _gains(k: Union[float, Sequence[float]], name: str) -> list:
    return [float(k)] * 3 if np.ndim(k) == 0 else _vec(k, 3, name)


class Mekf:
    """The multiplicative extended Kalman filter for the attitude and the gyro bias, from a
    rate gyro and star trackers (the scene's ``[fsw.estimator] kind = "mekf"``).

    ``noise_density`` (rad/s/√Hz) and ``bias_walk`` (rad/s²/√Hz) are the gyro's, as in the
    scene's ``[[sensors.gyro]]``; ``sigma_attitude`` (rad) and ``sigma_bias`` (rad/s) the
    initial 1-sigmas; ``attitude`` and ``bias`` the initial estimate (a first star tracker
    reading is the natural start; normalised, as :meth:`update`'s ``q``). ``gyro_model``: ``"continuous"`` (Farrenkopf's model,
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
        """Propagates over ``dt`` (s) with the gyro reading ``omega`` (rad/s) held; a result
        that is not finite raises :class:`satsim.SatsimError` and leaves the filter as it was."""
        self._native.propagate([float(x) for x in omega], float(dt))

    def update(self, q: Sequence[float], sigma: Union[float, Sequence[float]]) -> None:
        """A star tracker reading ``q`` ``[w, x, y, z]`` (normalised whatever its norm, as a
        scene's estimator takes a quantised reading; a zero or non-finite one is refused) with
        its 1-sigma ``sigma`` (rad, about the body's x, y, z axes; one number for all three;
        each >= 0, and raised to :data:`MIN_SIGMA` when below it, as a scene's estimator does,
        so that a noiseless star tracker's update stays well posed)."""
        s = [float(sigma)] * 3 if np.ndim(sigma) == 0 else [float(x) for x in sigma]
        self._native.update_attitude([float(x) for x in q], s)

    update_attitude = update

    def update_vector(self, body: Sequence[float], reference: Sequence[float],
                      sigma: float) -> None:
        """A direction measurement: ``body`` measured in the body's axes (a Sun sensor's
        direction, a magnetometer's field), ``reference`` the same direction in inertial
        axes from an on-board model (any units: both are normalised), with 1-sigma angular
        noise ``sigma`` (rad) about each axis across it. It corrects the attitude across the
        direction only: the rotation about it is not observed. For a magnetometer of noise
        ``σ_B`` (T), ``sigma = σ_B / |B|``. ``sigma`` >= 0 is raised to :data:`MIN_SIGMA` when
        below it, as a scene's estimator does for a noiseless Sun sensor or magnetometer. A
        zero vector (a Sun sensor in umbra) is refused."""
        self._native.update_vector(_vec(body, 3, "body"), _vec(reference, 3, "reference"),
                                   float(sigma))

    def set_attitude_covariance(self, p: Sequence[Sequence[float]]) -> None:
        """Sets the attitude block of the covariance (rad², body axes; 3 × 3, symmetric
        positive definite), its correlation with the bias to zero."""
        a = np.asarray(p, dtype=float)
        if a.shape != (3, 3):
            raise _satsim.SatsimError(f"the attitude covariance must be 3 x 3, not {a.shape}")
        self._native.set_attitude_covariance(a.tolist())

    @classmethod
    def from_triad(
        cls,
        b1: Sequence[float],
        b2: Sequence[float],
        r1: Sequence[float],
        r2: Sequence[float],
        sigma1: float,
        sigma2: float,
        *,
        noise_density: float,
        bias_walk: float,
        sigma_bias: float,
        bias: Sequence[float] = (0.0, 0.0, 0.0),
        gyro_model: str = "continuous",
    ) -> "Mekf":
        """A filter started from two directions, as the scene's ``[fsw.estimator] kind =
        "sun_mag"`` starts: the attitude by :func:`triad` (``b1``, ``b2`` measured in the
        body's axes, ``r1``, ``r2`` their inertial references; ``b1`` the primary, e.g. the
        Sun), its covariance by :func:`triad_covariance` for the 1-sigma angular noises
        ``sigma1``, ``sigma2`` (rad, >= 0; raised to :data:`MIN_SIGMA` as the scene's are) of
        ``b1`` and ``b2``; the bias as in the constructor."""
        p = triad_covariance(b1, b2, _floored_sigma(sigma1, "sigma1"),
                             _floored_sigma(sigma2, "sigma2"))
        q = triad(b1, b2, r1, r2)
        f = cls(noise_density=noise_density, bias_walk=bias_walk,
                sigma_attitude=float(np.sqrt(np.max(np.diag(p)))), sigma_bias=sigma_bias,
                attitude=q, bias=bias, gyro_model=gyro_model)
        f.set_attitude_covariance(p)
        return f

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
    ``q_true = q_est ⊗ exp(δθ/2)``: its norm is the estimate's error angle. The quaternions
    are normalised whatever their norm (a quantised star tracker's reading may be compared);
    a zero or non-finite one raises :class:`satsim.SatsimError`."""
    return np.array(_satsim.attitude_error([float(x) for x in q_est], [float(x) for x in q_true]))


def triad(b1: Sequence[float], b2: Sequence[float], r1: Sequence[float],
          r2: Sequence[float]) -> np.ndarray:
    """TRIAD: the attitude ``[w, x, y, z]`` (body to inertial, ``w >= 0``) from two
    directions measured in the body's axes, ``b1`` (the primary, mapped exactly:
    ``R(q) b1/|b1| = r1/|r1|``) and ``b2``, and the same directions in inertial axes, ``r1``
    and ``r2``. Any lengths (only the directions count). A zero or non-finite vector, or a
    (nearly) parallel pair (the sine of their angle below 1e-3), raises
    :class:`satsim.SatsimError`."""
    return np.array(_satsim.triad(_vec(b1, 3, "b1"), _vec(b2, 3, "b2"), _vec(r1, 3, "r1"),
                                  _vec(r2, 3, "r2")))


def triad_covariance(b1: Sequence[float], b2: Sequence[float], sigma1: float,
                     sigma2: float) -> np.ndarray:
    """The 3 × 3 covariance (rad², body axes) of :func:`triad`'s attitude error ``δθ`` for the
    body directions ``b1`` (primary) and ``b2`` with 1-sigma angular noises ``sigma1`` and
    ``sigma2`` (rad, about each axis across the direction), Shuster & Oh (1981)::

        P = σ1² I + |b1 × b2|⁻² [(σ2² − σ1²) b1 b1ᵀ + σ1² (b1 · b2)(b1 b2ᵀ + b2 b1ᵀ)]

    (``b1``, ``b2`` normalised)."""
    return _satsim.triad_covariance(_vec(b1, 3, "b1"), _vec(b2, 3, "b2"), float(sigma1),
                                    float(sigma2))


def gyro_mean(before: Sequence[float], after: Sequence[float]) -> np.ndarray:
    """The rate (rad/s) the scene's estimator propagates with over a gyro period: the mean of
    the readings at its two ends."""
    return np.array(_satsim.gyro_mean(_vec(before, 3, "before"), _vec(after, 3, "after")))


def bdot_dipole(gain: float, b_prev: Sequence[float], b: Sequence[float],
                dt: float) -> np.ndarray:
    """The B-dot dipole (A m², body axes) ``−gain (b − b_prev) / dt`` from two magnetometer
    readings (T, body axes) ``dt`` seconds apart (``[fsw.bdot]``; ``gain`` in A m² s/T, > 0)."""
    return np.array(_satsim.bdot_dipole(float(gain), _vec(b_prev, 3, "b_prev"), _vec(b, 3, "b"),
                                        float(dt)))


def momentum_dipole(gain: float, h: Sequence[float], b: Sequence[float]) -> np.ndarray:
    """The momentum-dumping dipole (A m², body axes) ``gain (h × b) / |b|²`` for the wheels'
    momentum ``h`` (N m s) and the field ``b`` (T), both body axes (``[fsw.momentum]``;
    ``gain`` in 1/s, > 0); zero where ``b`` is zero."""
    return np.array(_satsim.momentum_dipole(float(gain), _vec(h, 3, "h"), _vec(b, 3, "b")))


class Reference:
    """A reference: ``attitude`` ``[w, x, y, z]`` (body to inertial, ``w >= 0``), ``rate``
    (rad/s, the reference's own axes) and ``acceleration`` (rad/s², the time derivative of
    ``rate``'s components), as numpy arrays. Also readable as ``ref["attitude"]`` and
    unpackable as ``attitude, rate, acceleration = ref``."""

    __slots__ = ("attitude", "rate", "acceleration")

    def __init__(self, attitude: Sequence[float], rate: Sequence[float] = (0.0, 0.0, 0.0),
                 acceleration: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        self.attitude = np.array(attitude, dtype=float)
        self.rate = np.array(rate, dtype=float)
        self.acceleration = np.array(acceleration, dtype=float)

    def __getitem__(self, key: str) -> np.ndarray:
        if key not in self.__slots__:
            raise KeyError(key)
        return getattr(self, key)

    def __iter__(self):
        return iter((self.attitude, self.rate, self.acceleration))

    def __repr__(self) -> str:
        return (f"satsim.fsw.Reference(attitude={self.attitude.tolist()}, "
                f"rate={self.rate.tolist()}, acceleration={self.acceleration.tolist()})")


def _reference(x) -> tuple:
    """``x`` (a :class:`Reference`, a dict with its keys, or a quaternion) as the three lists."""
    if isinstance(x, Reference):
        a, w, d = x.attitude, x.rate, x.acceleration
    elif isinstance(x, dict):
        a, w, d = x["attitude"], x.get("rate", (0.0, 0.0, 0.0)), x.get(
            "acceleration", (0.0, 0.0, 0.0))
    else:
        a, w, d = x, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    return _vec(a, 4, "the reference's attitude"), _vec(w, 3, "the reference's rate"), _vec(
        d, 3, "the reference's acceleration")


class Guidance:
    """A guidance law: the reference attitude, rate and acceleration the control points the
    body at (the scene's ``[fsw.guidance] mode``). Build one with :meth:`inertial`,
    :meth:`nadir`, :meth:`sun` or :meth:`target`; ask it with :meth:`reference`."""

    __slots__ = ("_native",)

    def __init__(self, native) -> None:
        self._native = native

    @classmethod
    def inertial(cls, q: Sequence[float]) -> "Guidance":
        """A fixed attitude ``q`` ``[w, x, y, z]`` (body to inertial; within 1e-3 of unit norm it
        is normalised, with a :class:`UserWarning` when more than rounding off; beyond, a
        :class:`satsim.SatsimError`, as a scene's quaternions): zero rate and acceleration;
        needs no orbit."""
        return cls(_satsim.NativeGuidance.inertial(_vec(q, 4, "q")))

    @classmethod
    def nadir(cls, offset: Optional[Sequence[float]] = None) -> "Guidance":
        """The local orbital frame (LVLH: z towards the Earth's centre, y along ``−r × v``,
        x = y × z) times the fixed ``offset`` ``[w, x, y, z]`` (body to orbital; none: the
        identity; normalised or refused as :meth:`inertial`'s ``q``), turning at ``r × v / r²``."""
        q = (1.0, 0.0, 0.0, 0.0) if offset is None else offset
        return cls(_satsim.NativeGuidance.nadir(_vec(q, 4, "offset")))

    @classmethod
    def sun(cls, axis: Sequence[float], secondary: Sequence[float], epoch: str) -> "Guidance":
        """Body ``axis`` on the direction from the spacecraft to the Sun, turned about it so
        that body ``secondary`` lies nearest the orbit normal ``r × v``; ``t = 0`` at
        ``epoch`` (as a scene's, e.g. ``"2026-03-20T12:00:00 UTC"``)."""
        return cls(_satsim.NativeGuidance.sun(_vec(axis, 3, "axis"),
                                              _vec(secondary, 3, "secondary"), str(epoch)))

    @classmethod
    def target(cls, latitude_deg: float, longitude_deg: float, altitude: float = 0.0,
               axis: Sequence[float] = (0.0, 0.0, 1.0),
               secondary: Sequence[float] = (0.0, -1.0, 0.0), *,
               epoch: str) -> "Guidance":
        """Body ``axis`` on the point at geodetic WGS-84 latitude and longitude (degrees) and
        ``altitude`` (m above the ellipsoid) fixed on the rotating Earth, ``secondary``
        nearest the orbit normal; the Earth's rotation at ``epoch`` + ``t``. The defaults
        (+z at it, −y nearest the normal) give the orbital frame for the point below."""
        return cls(_satsim.NativeGuidance.target(
            float(latitude_deg), float(longitude_deg), float(altitude), _vec(axis, 3, "axis"),
            _vec(secondary, 3, "secondary"), str(epoch)))

    @property
    def kind(self) -> str:
        """``"inertial"``, ``"nadir"``, ``"sun"`` or ``"target"``."""
        return self._native.kind

    @property
    def needs_orbit(self) -> bool:
        """Whether :meth:`reference` needs ``r`` and ``v`` (all but inertial)."""
        return self._native.needs_orbit

    def reference(self, t: float = 0.0, r: Optional[Sequence[float]] = None,
                  v: Optional[Sequence[float]] = None, mu: float = MU_EARTH) -> Reference:
        """The :class:`Reference` at ``t`` seconds from the law's epoch where the spacecraft is
        at ``r`` (m) moving at ``v`` (m/s), GCRF, about a body of gravitational parameter
        ``mu`` (m³/s², for nadir's acceleration). A law that needs the orbit and has none, or
        a spacecraft at the point it should look at, raises :class:`satsim.SatsimError`."""
        q, w, a = self._native.reference(
            float(t), None if r is None else _vec(r, 3, "r"),
            None if v is None else _vec(v, 3, "v"), float(mu))
        return Reference(q, w, a)

    def __repr__(self) -> str:
        return f"satsim.fsw.Guidance({self.kind})"


class Slew:
    """Shapes a reference so that it moves towards its target within ``max_rate`` (rad/s) and
    ``max_acceleration`` (rad/s²) relative to it (the scene's ``[fsw.guidance] max_rate``,
    ``max_acceleration``; one of them may be ``inf``). An eigenaxis slew from rest; a moving
    target is followed at its own rate plus the slew."""

    __slots__ = ("_native",)

    def __init__(self, max_rate: float, max_acceleration: float) -> None:
        self._native = _satsim.NativeSlew(float(max_rate), float(max_acceleration))

    def reset(self, attitude: Sequence[float], rate: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        """Starts again from the spacecraft's ``attitude`` ``[w, x, y, z]`` (body to inertial;
        normalised within 1e-3 of unit norm, refused beyond, as :meth:`Guidance.inertial`'s
        ``q``) and body ``rate`` (rad/s) now: the next :meth:`step` returns them without
        advancing. Never reset, the shaper starts at its first target."""
        self._native.reset(_vec(attitude, 4, "attitude"), _vec(rate, 3, "rate"))

    def step(self, reference, dt: float) -> Reference:
        """The shaped :class:`Reference` at the instant of the target ``reference`` (a
        :class:`Reference`, a dict with its keys or a bare attitude ``[w, x, y, z]``; its
        attitude normalised or refused as :meth:`reset`'s), ``dt`` seconds (>= 0) after the
        previous step."""
        q, w, a = self._native.step(*_reference(reference), float(dt))
        return Reference(q, w, a)

    @property
    def max_rate(self) -> float:
        return self._native.max_rate

    @property
    def max_acceleration(self) -> float:
        return self._native.max_acceleration

    @property
    def relative_rate(self) -> Optional[np.ndarray]:
        """The rate relative to the target held over the last step (rad/s, shaped axes);
        ``None`` before the first step."""
        w = self._native.relative_rate
        return None if w is None else np.array(w)

    @property
    def remaining_angle(self) -> Optional[float]:
        """The angle (rad) between the shaped reference and the target at the last step."""
        return self._native.remaining_angle


class Pid:
    """The attitude PID of ``[fsw.control] kind = "pid"`` and its least-squares allocation to
    reaction wheels. Gains (one number, or one per body axis; >= 0): ``kp`` (N m/rad), ``ki``
    (N m/(rad s)), ``kd`` (N m s/rad); ``inertia`` (3 × 3, kg m², body axes) adds the
    gyroscopic feed-forward ``ω̂ × (J ω̂)``. With the error ``e = log(q_ref* ⊗ q_est)``::

        u = −kp∘e − ki∘∫e dt − kd∘(ω̂ − ω_ref,b) + ω̂ × (J ω̂)

    the integral clamped to ``±capability/ki`` per axis (anti-windup, once wheels are
    allocated)."""

    __slots__ = ("_native",)

    def __init__(self, kp: Union[float, Sequence[float]], ki: Union[float, Sequence[float]],
                 kd: Union[float, Sequence[float]],
                 inertia: Optional[Sequence[Sequence[float]]] = None) -> None:
        j = None
        if inertia is not None:
            a = np.asarray(inertia, dtype=float)
            if a.shape != (3, 3):
                raise _satsim.SatsimError(f"the inertia must be 3 x 3, not {a.shape}")
            j = a.tolist()
        self._native = _satsim.NativePid(_gains(kp, "kp"), _gains(ki, "ki"),
                                         _gains(kd, "kd"), j)

    def allocate(self, axes: Sequence[Sequence[float]],
                 max_torque: Union[float, Sequence[float]] = float("inf")) -> None:
        """Sets the wheels: their spin axes (body axes, k × 3; normalised) and motor torque
        limits (N m; one number for all, ``inf`` for none)."""
        a = np.asarray(axes, dtype=float).reshape(-1, 3)
        m = [float(max_torque)] * len(a) if np.ndim(max_torque) == 0 else [
            float(x) for x in max_torque]
        self._native.allocate(a.tolist(), m)

    def reset(self) -> None:
        """Starts afresh: the integral back to zero."""
        self._native.reset()

    def torque(self, q_est: Sequence[float], w_est: Sequence[float], q_ref: Sequence[float],
               w_ref: Sequence[float] = (0.0, 0.0, 0.0), dt: float = 0.0) -> np.ndarray:
        """One control sample: the wanted body torque ``u`` (N m, body axes) from the estimate
        ``q_est`` ``[w, x, y, z]`` (body to inertial) and rate ``w_est`` (rad/s, body axes),
        the reference ``q_ref`` and its rate ``w_ref`` (rad/s, the reference's axes), over the
        sample period ``dt`` (s, the integral's step). ``q_est`` and ``q_ref`` are normalised
        within 1e-3 of unit norm (a :class:`UserWarning` when off by more than rounding) and
        refused beyond with :class:`satsim.SatsimError`, as a scene's quaternions."""
        return np.array(self._native.torque(
            _vec(q_est, 4, "q_est"), _vec(w_est, 3, "w_est"), _vec(q_ref, 4, "q_ref"),
            _vec(w_ref, 3, "w_ref"), float(dt)))

    def commands(self, u: Sequence[float]) -> np.ndarray:
        """The wheels' motor torque commands (N m, one per allocated wheel, in order) that put
        the body torque ``u`` on the body (the wheels apply ``−Σ τ_j a_j``), scaled down as a
        whole when one would exceed its limit."""
        return np.array(self._native.commands(_vec(u, 3, "u")))

    @property
    def capability(self) -> np.ndarray:
        """The largest torque the wheels make about each body axis (N m; ``inf`` unallocated)."""
        return np.array(self._native.capability)

    @property
    def integral(self) -> np.ndarray:
        """``∫ e dt`` so far (rad s)."""
        return np.array(self._native.integral)

    @property
    def n_wheels(self) -> int:
        return self._native.n_wheels
