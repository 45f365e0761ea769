"""The peer-comparison spacecraft (orbit.toml) in Basilisk (`pip install bsk`), for peers.py.

The hub is `spacecraft.Spacecraft`'s hub (the bus); the hinge chain h1..h5 is one
`SpinningBodyNDOFStateEffector` with five spinning bodies in chain order (h1, h2 massless and
zero-length, as in the model file; each spinning body's frame S at its hinge point, the
centre of mass at r_ScS_S); the wheels are `ReactionWheelStateEffector` balanced wheels with
no motor torque. Basilisk integrates with its default RK4 at the task rate (dt). Written for
this scene only (examples/satellite.toml's layout: hinge points on the panels' y axes).
"""

import math
import time

import numpy as np


def available():
    from Basilisk import __version__  # noqa: F401
    from Basilisk.simulation import spinningBodyNDOFStateEffector  # noqa: F401

    return True


def _build(scene_path, duration, dt):
    from Basilisk.simulation import reactionWheelStateEffector, spacecraft, spinningBodyNDOFStateEffector
    from Basilisk.utilities import SimulationBaseClass, macros, simIncludeRW

    import mjcf

    scene, model = mjcf.load(scene_path)
    bodies = {b["name"]: b for b in model["body"]}
    hinges = model["hinge"]
    ini = scene["initial"]
    fx = scene["effects"]
    k, c = fx["hinge_springs"]["stiffness"], fx["hinge_springs"]["damping"]

    sim = SimulationBaseClass.SimBaseClass()
    proc = sim.CreateNewProcess("p")
    proc.addTask(sim.CreateNewTask("t", macros.sec2nano(dt)))
    sc = spacecraft.Spacecraft()
    bus = model["body"][0]
    # Basilisk's balanced wheels add only their spin to the dynamics: the wheels' mass and
    # locked inertia belong to the hub (measured: with them in the hub the attitude agrees
    # with satsim to 1e-13 over 600 s without wheel spin; without them, to 1e-4 only).
    wheels = fx.get("reaction_wheels", {}).get("wheel", [])
    parts = [(bus["mass"], np.zeros(3), np.array(bus["inertia"], dtype=float))]
    for w in wheels:
        a = np.array(w["axis"], dtype=float)
        a /= np.linalg.norm(a)
        aat = np.outer(a, a)
        jt = w.get("transverse", 0.5 * w["inertia"])
        parts.append((w.get("mass", 0.0), np.array(w.get("at", [0.0] * 3), dtype=float),
                      w["inertia"] * aat + jt * (np.eye(3) - aat)))
    m_hub = sum(p[0] for p in parts)
    com = sum(p[0] * p[1] for p in parts) / m_hub
    hub_i = np.zeros((3, 3))
    for m, r, i in parts:
        d = r - com
        hub_i += i + m * (d @ d * np.eye(3) - np.outer(d, d))
    sc.hub.mHub = m_hub
    sc.hub.r_BcB_B = [[x] for x in com]
    sc.hub.IHubPntBc_B = hub_i.tolist()
    sc.hub.sigma_BNInit = [[0.0], [0.0], [0.0]]
    sc.hub.omega_BN_BInit = [[w] for w in ini["base"]["angular_velocity"]]

    chain = spinningBodyNDOFStateEffector.SpinningBodyNDOFStateEffector()
    prev_child_at = [0.0, 0.0, 0.0]
    angles, rates = ini["hinges"]["angle"], ini["hinges"]["rate"]
    for i, h in enumerate(hinges):
        b = bodies[h["child"]]
        child_at = h.get("child_at", [0.0, 0.0, 0.0])
        at = h.get("at", [0.0, 0.0, 0.0])
        sb = spinningBodyNDOFStateEffector.SpinningBody()
        sb.setMass(b["mass"])
        sb.setISPntSc_S(b["inertia"])
        sb.setDCM_S0P([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
        # S at the hinge point: the centre of mass is -child_at from it; the hinge point in
        # the previous S frame is `at` less the previous body's child_at.
        sb.setR_ScS_S([[-x] for x in child_at])
        sb.setR_SP_P([[a - p] for a, p in zip(at, prev_child_at)])
        sb.setSHat_S([[x] for x in h["axis"]])
        sb.setThetaInit(angles[i])
        sb.setThetaDotInit(rates[i])
        sb.setK(k[i])
        sb.setC(c[i])
        chain.addSpinningBody(sb)
        prev_child_at = child_at
    sc.addStateEffector(chain)

    factory = simIncludeRW.rwFactory()
    for w in fx.get("reaction_wheels", {}).get("wheel", []):
        rwc = factory.create(
            "custom",
            w["axis"],
            Omega=w.get("speed", 0.0) * 60.0 / (2.0 * math.pi),  # rpm
            rWB_B=w.get("at", [0.0, 0.0, 0.0]),
            Js=w["inertia"],
            RWModel=reactionWheelStateEffector.BalancedWheels,
            u_max=-1.0,
            Omega_max=-1.0,
            useMaxTorque=False,
            useRWfriction=False,
        )
        # Mass and transverse inertia are in the hub (above), not on the wheel.
        rwc.mass = 0.0
        rwc.Jt = rwc.Jg = w.get("transverse", 0.5 * w["inertia"])
    rw = reactionWheelStateEffector.ReactionWheelStateEffector()
    if factory.rwList:
        factory.addToSpacecraft("rw", rw, sc)
    sim.AddModelToTask("t", sc)
    sim.AddModelToTask("t", chain)
    sim.AddModelToTask("t", rw)
    rec = sc.scStateOutMsg.recorder(macros.sec2nano(duration))
    sim.AddModelToTask("t", rec)
    sim.InitializeSimulation()
    sim.ConfigureStopTime(macros.sec2nano(duration))
    return sim, sc, chain, rw, rec


def time_orbit(scene_path, duration, dt):
    """Seconds of `ExecuteSimulation` for one run."""
    sim, *_ = _build(scene_path, duration, dt)
    t0 = time.perf_counter()
    sim.ExecuteSimulation()
    return time.perf_counter() - t0


def validate(scene_path, satsim_run, scene_variant, tmp, duration=600.0, dt=0.1):
    """(message, largest difference): the hub attitude and rates after `duration` against
    satsim's, both RK4 at `dt`."""
    sim, sc, chain, rw, rec = _build(scene_path, duration, dt)
    sim.ExecuteSimulation()
    sigma = np.array(rec.sigma_BN[-1])
    s2 = sigma @ sigma
    q = np.array([(1 - s2), *(2 * sigma)]) / (1 + s2)  # MRP -> [w, x, y, z]
    _, _, rows = satsim_run(scene_variant(tmp, duration, dt, duration), f"{tmp}/bsk_val")
    ref = np.array([rows[-1][k] for k in ("q_w", "q_x", "q_y", "q_z")])
    if q @ ref < 0:
        q = -q
    omega = np.array(rec.omega_BN_B[-1])
    ref_w = np.array([rows[-1][k] for k in ("omega_x", "omega_y", "omega_z")])
    dq, dw = np.abs(q - ref).max(), np.abs(omega - ref_w).max()
    return (
        f"validation: Basilisk vs satsim after {duration} s (RK4 dt = {dt} s): "
        f"max |dq| = {dq:.2e}, max |d omega| = {dw:.2e} rad/s",
        max(dq, dw),
    )
