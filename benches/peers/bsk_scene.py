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
    sc.hub.mHub = bus["mass"]
    sc.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    sc.hub.IHubPntBc_B = bus["inertia"]
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
    for w in fx["reaction_wheels"]["wheel"]:
        factory.create(
            "custom",
            w["axis"],
            Omega=w.get("speed", 0.0) * 60.0 / (2.0 * math.pi),  # rpm
            rWB_B=w.get("at", [0.0, 0.0, 0.0]),
            Js=w["inertia"],
            Jt=w.get("transverse", 0.5 * w["inertia"]),
            Jg=w.get("transverse", 0.5 * w["inertia"]),
            mass=w.get("mass", 0.0),
            RWModel=reactionWheelStateEffector.BalancedWheels,
            u_max=-1.0,
            Omega_max=-1.0,
            useMaxTorque=False,
            useRWfriction=False,
        )
    rw = reactionWheelStateEffector.ReactionWheelStateEffector()
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
    """The hub attitude after `duration` against satsim's (reported, not gated)."""
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
    return (
        f"Basilisk vs satsim after {duration} s (RK4 dt = {dt} s, not gated): "
        f"|dq| = {np.abs(q - ref).max():.2e}, |d omega| = {np.abs(omega - ref_w).max():.2e} rad/s"
    )
