"""Monte Carlo of your own flight software: satsim against Basilisk, side by side. Not run by
cargo or CI (a peer benchmark, like peers.py; it needs `pip install bsk` and the satsim Python
module in the same environment).

    python3 benches/peers/fsw_mc.py [--runs 8] [--rounds 3] [--duration 600] [--cores N]
                                    [--json PATH] [--plain-loop]

The spacecraft is examples/scenes/fsw_in_the_loop.toml: the preprint satellite (bus, a
three-panel array on a 3-DOF hinge and two 1-DOF hinges) deploying under its hinge springs,
latch stops on h4/h5, three reaction wheels with friction and torque/speed limits, gravity
gradient on a 500 km Kepler orbit, RK4 at 0.01 s, 600 s, and a 10 Hz attitude controller: the
law of examples/python/fsw_in_the_loop.py on the true state,

    u = -kp * 2 sgn(q_w) q_xyz - kd * omega,   wheel commands = -u,   kp = 9, kd = 150.

Each run disperses the bus's initial rate (N(0, 0.001 rad/s) on each axis: numpy draws for
Basilisk, the plain loops and satsim.run; the campaign's own draws, a [campaign] table with
the same law, for satsim.campaign). The differences from the satsim scene that Basilisk
cannot model (latch stops, the friction law, per-body gravity gradient) are listed in
fsw_mc.md. What is measured,
in ROUNDS alternating rounds (medians reported):

(a) Basilisk: the same spacecraft (bsk_scene._build: hinge chain as one
    SpinningBodyNDOFStateEffector, wheels as ReactionWheelStateEffector; here with the
    scene's wheel friction and limits, point-mass Earth gravity on the Kepler orbit's initial
    state and GravityGradientEffector), flown by Basilisk's own C flight software in a 0.1 s
    task: simpleNav (no noise: the truth) -> inertial3D -> attTrackingError -> mrpFeedback ->
    rwMotorTorque -> the wheels, dynamics RK4 at 0.01 s. The gains are the satsim law's to
    first order: mrpFeedback's torque is -K sigma - P omega (Ki < 0: no integral; with the
    reference at rest its gyroscopic terms vanish), and the MRP sigma = q_xyz / (1 + q_w)
    is q_xyz / 2 near the target, so K = 4 kp = 36 N m and P = kd = 150 N m s. RUNS runs in
    one process, each a fresh SimBaseClass built, initialised and executed as the
    `Basilisk.utilities.MonteCarlo.Controller` would for one run (its creation function,
    then its execution function), timed from the start of the build. This sequential loop
    is conservative in Basilisk's favour: the Controller adds its bookkeeping, the
    dispersion machinery and the pickling of retained data on top. The pointing error at
    the end of each run is printed, so the comparison is of a working controller.
(b) satsim, same runs, the law in Python at 10 Hz, one process: `satsim.campaign(...,
    controller=make_fsw, period=0.1)` (in this process) when the installed module has the
    Python-controlled campaign, else (fallback) a plain `satsim.Simulation` loop per run
    (measure(), row(), the law, set_inputs(), advance(0.1)), the contract's loop; that
    loop also with --plain-loop.
(c) the Python overhead per tick (6000 ticks per 600 s run): the runs of (b) with a
    controller that returns {} every tick against `satsim.run` of the scene with the built-in
    controller disabled (the same dynamics: the wheels idle either way, no Python in the
    loop); and with the law against `satsim.run` with the built-in discrete controller
    enabled (the same law in Rust: the same trajectory to round-off).
(d) all cores (--cores, default os.cpu_count()), only with the campaign API:
    `satsim.campaign(..., workers=N)` against N independent processes of this script
    (`--worker I/N`), each running the plain Simulation loop over its share of the runs,
    processes' start-up included; throughput of the first as a percentage of the second.

Runs per core-second = runs / wall seconds of a single-process loop (build included).
"""

from __future__ import annotations

import argparse
import contextlib
import inspect
import json
import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
SCENES = ROOT / "examples" / "scenes"
SCENE = SCENES / "fsw_in_the_loop.toml"
BUILT_IN = "period = 0.1             # s: the flight software's rate (zero-order hold)"
BASE_LINE = "base = { attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.0, 0.0, 0.0] }"
KP, KD, PERIOD = 9.0, 150.0, 0.1
K_MRP, P_MRP = 4.0 * KP, KD  # mrpFeedback's gains: -K sigma - P omega, sigma ~ q_xyz / 2
SIGMA_RATE = 0.001  # rad/s, each axis of the initial bus rate
DT = 0.01  # s: RK4 step (the scene's)
MU_EARTH = 3.986004418e14  # satsim's (crates/spacecraft/src/effects/orbit.rs)
R_EARTH = 6_378_137.0


# --- The flight software (module level: a campaign's workers import it) -------------------


def law(q, omega):
    """The wheels' motor commands (N m) for attitude q = [w, x, y, z] and rate omega (rad/s):
    examples/python/fsw_in_the_loop.py's law."""
    s = -1.0 if q[0] < 0.0 else 1.0
    u = [-KP * 2.0 * s * q[1 + i] - KD * omega[i] for i in range(3)]
    return {"wheel_x": -u[0], "wheel_y": -u[1], "wheel_z": -u[2]}


class Fsw:
    """The law on the true state (row), as Basilisk's side reads the truth (simpleNav, no
    noise)."""

    def step(self, t, meas, row):
        return law((row["q_w"], row["q_x"], row["q_y"], row["q_z"]),
                   (row["omega_x"], row["omega_y"], row["omega_z"]))


class Idle:
    """A controller that commands nothing: the per-tick cost of the Python loop alone."""

    def step(self, t, meas, row):
        return {}


def make_fsw(run):
    return Fsw()


def make_idle(run):
    return Idle()


# --- Scenes and draws ------------------------------------------------------------------------


def draws(runs, seed=1):
    """The initial bus rate of each run (rad/s), the same for Basilisk and satsim's loop."""
    return np.random.default_rng(seed).normal(0.0, SIGMA_RATE, (runs, 3))


def scene_text(duration, controller=False, omega=None, campaign_runs=None, seed=1):
    """fsw_in_the_loop.toml with `duration`, the built-in controller off (default) or on, the
    initial rate `omega` and, with `campaign_runs`, a [campaign] table dispersing it."""
    text = SCENE.read_text()
    assert "duration = 600.0" in text and BUILT_IN in text and BASE_LINE in text
    text = text.replace("duration = 600.0", f"duration = {float(duration)!r}", 1)
    if not controller:
        text = text.replace(BUILT_IN, BUILT_IN + "\nenabled = false", 1)
    if omega is not None:
        w = ", ".join(repr(float(x)) for x in omega)
        text = text.replace(BASE_LINE, BASE_LINE.replace("[0.0, 0.0, 0.0] }", f"[{w}] }}"), 1)
    if campaign_runs is not None:
        text += (f"\n[campaign]\nruns = {campaign_runs}\nseed = {seed}\n"
                 f'[[campaign.disperse]]\nkey = "initial.base.angular_velocity"\n'
                 f"normal = {{ sigma = {SIGMA_RATE} }}\n")
    return text


def pointing_error_arcsec(qw):
    return math.degrees(2.0 * math.acos(min(abs(qw), 1.0))) * 3600.0


# --- satsim ----------------------------------------------------------------------------------


def campaign_api(factory):
    """("", True) when the installed satsim.campaign flies a Python controller (a one-run,
    0.2 s campaign with `factory` is tried), else (why not, False)."""
    import satsim

    if "controller" not in inspect.signature(satsim.campaign).parameters:
        return "satsim.campaign takes no controller", False
    try:
        satsim_campaign(0.2, 1, factory, None)
    except Exception as e:  # an API still under construction: fall back, say why
        return f"satsim.campaign(controller=...) failed: {type(e).__name__}: {e}", False
    return "", True


def _workers_kw(n):
    """None: the runs in this process; N: N worker processes."""
    if n is None:
        return {}
    import satsim

    params = inspect.signature(satsim.campaign).parameters
    return {"workers": n} if "workers" in params else {"threads": n}


def satsim_loop(text, controller):
    """One run of the contract's loop (measure, row, step, set_inputs, advance) in a
    satsim.Simulation; the final pointing error (arcsec)."""
    import satsim

    with satsim.Simulation(text, base_dir=SCENES) as sim:
        end = sim.t_end
        while sim.t < end - 1e-9:
            cmd = controller.step(sim.t, sim.measure(), sim.row())
            if cmd:
                sim.set_inputs(cmd)
            sim.advance(PERIOD)
        return pointing_error_arcsec(sim.row()["q_w"])


def satsim_loops(duration, omegas, controller, runs=None):
    """`runs` (indices) of the plain Simulation loop; the final pointing errors."""
    runs = range(len(omegas)) if runs is None else runs
    return [satsim_loop(scene_text(duration, omega=omegas[k]), controller) for k in runs]


def satsim_runs(duration, omegas, controller):
    """satsim.run of each run's scene, no Python in the loop (built-in controller on/off)."""
    import satsim

    errs = []
    for w in omegas:
        r = satsim.run(scene_text(duration, controller=controller, omega=w), base_dir=SCENES)
        errs.append(pointing_error_arcsec(r["q_w"][-1]))
    return errs


def satsim_campaign(duration, runs, factory, workers):
    """The Python-controlled campaign; the final pointing errors where the table has q_w."""
    import satsim

    res = satsim.campaign(scene_text(duration, campaign_runs=runs), controller=factory,
                          period=PERIOD, out=None, base_dir=SCENES, **_workers_kw(workers))
    table = getattr(res, "table", res)
    if hasattr(table, "status"):
        bad = [s for s in table.status if s != "ok"]
        if bad:
            raise SystemExit(f"campaign: {len(bad)} runs failed: {table.messages[:3]}")
    for col in ("final_q_w", "q_w"):
        if col in table:
            return [pointing_error_arcsec(x) for x in table[col]]
    return []


def worker_main(spec, duration, runs, seed):
    """--worker I/N: runs k % N == I of the plain loop with the law."""
    i, n = (int(x) for x in spec.split("/"))
    omegas = draws(runs, seed)
    errs = satsim_loops(duration, omegas, Fsw(), runs=range(i, runs, n))
    print(json.dumps({"worker": spec, "runs": len(errs), "max_err_arcsec": max(errs, default=0)}))


def processes(duration, runs, cores, seed):
    """Wall seconds of `cores` independent processes of the plain loop, start-up included."""
    t0 = time.perf_counter()
    procs = [subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--worker",
                               f"{i}/{cores}", "--runs", str(runs), "--duration", str(duration),
                               "--seed", str(seed)], stdout=subprocess.PIPE, text=True)
             for i in range(cores)]
    outs = [p.communicate()[0] for p in procs]
    wall = time.perf_counter() - t0
    if any(p.returncode for p in procs):
        raise SystemExit(f"a worker process failed: {outs}")
    return wall


# --- Basilisk --------------------------------------------------------------------------------


@contextlib.contextmanager
def _bsk_build_hooks(wheels):
    """While bsk_scene._build runs: its SimBaseClass defers InitializeSimulation (so that the
    flight software, gravity and the dispersed state can be added before it), and its wheel
    factory gives the wheels the scene's torque and speed limits and friction."""
    from Basilisk.utilities import SimulationBaseClass, simIncludeRW

    base_sim, base_factory = SimulationBaseClass.SimBaseClass, simIncludeRW.rwFactory

    class DeferredSim(base_sim):
        defer = True

        def InitializeSimulation(self):
            if not self.defer:
                super().InitializeSimulation()

    class SceneWheels(base_factory):
        def create(self, rwType, gsHat_B, **kwargs):
            w = wheels[len(self.rwList)]
            rwc = super().create(rwType, gsHat_B, **kwargs)
            rwc.u_max = float(w.get("max_torque", -1.0))
            rwc.Omega_max = float(w.get("max_speed", -1.0))  # rad/s
            # satsim: (a0 + a1 exp(-(W/W0)^2)) sgn W + a2 W, stiction as events; Basilisk's
            # Stribeck model peaks at fStatic = a0 + a1 at W = betaStatic (see the notes).
            rwc.fCoulomb = float(w.get("coulomb", 0.0))
            rwc.cViscous = float(w.get("viscous", 0.0))
            if w.get("stribeck", 0.0) > 0.0:
                rwc.fStatic = float(w["coulomb"] + w["stribeck"])
                rwc.betaStatic = float(w.get("stribeck_speed", 1.0))
            return rwc

    SimulationBaseClass.SimBaseClass, simIncludeRW.rwFactory = DeferredSim, SceneWheels
    try:
        yield
    finally:
        SimulationBaseClass.SimBaseClass, simIncludeRW.rwFactory = base_sim, base_factory


def bsk_build(duration, omega0):
    """A fresh Basilisk simulation of the scene with its C flight software, not initialised:
    (sim, recorder of the hub states)."""
    if str(HERE) not in sys.path:
        sys.path.insert(0, str(HERE))
    import bsk_scene
    import mjcf
    from Basilisk.architecture import messaging
    from Basilisk.fswAlgorithms import attTrackingError, inertial3D, mrpFeedback, rwMotorTorque
    from Basilisk.simulation import GravityGradientEffector, simpleNav
    from Basilisk.utilities import fswSetupRW, macros, orbitalMotion, simIncludeGravBody

    scene, model = mjcf.load(SCENE)
    wheels = scene["effects"]["reaction_wheels"]["wheel"]
    with _bsk_build_hooks(wheels):
        sim, sc, chain, rw, rec = bsk_scene._build(SCENE, duration, DT)
    keep = []  # Python objects Basilisk only points to

    sc.hub.omega_BN_BInit = [[float(w)] for w in omega0]

    # The orbit: point-mass Earth, the Kepler elements' initial state, gravity gradient.
    orb = scene["orbit"]
    grav = simIncludeGravBody.gravBodyFactory()
    earth = grav.createEarth()
    earth.isCentralBody = True
    earth.mu = MU_EARTH
    earth.radEquator = R_EARTH
    grav.addBodiesTo(sc)
    oe = orbitalMotion.ClassicElements()
    oe.a = R_EARTH + orb["altitude"]
    oe.e = 0.0
    oe.i = math.radians(orb.get("inclination_deg", 0.0))
    oe.Omega = oe.omega = oe.f = 0.0
    r, v = orbitalMotion.elem2rv(MU_EARTH, oe)
    sc.hub.r_CN_NInit = [[x] for x in r]
    sc.hub.v_CN_NInit = [[x] for x in v]
    gg = GravityGradientEffector.GravityGradientEffector()
    gg.ModelTag = "gravityGradient"
    gg.addPlanetName(earth.planetName)
    sc.addDynamicEffector(gg)
    sim.AddModelToTask("t", gg)
    keep += [grav, earth, gg]

    # The flight software: a 0.1 s task in its own process.
    fsw = sim.CreateNewProcess("fsw")
    fsw.addTask(sim.CreateNewTask("fswTask", macros.sec2nano(PERIOD)))
    nav = simpleNav.SimpleNav()
    nav.ModelTag = "nav"
    nav.scStateInMsg.subscribeTo(sc.scStateOutMsg)
    ref = inertial3D.inertial3D()
    ref.ModelTag = "inertial3D"
    ref.sigma_R0N = [0.0, 0.0, 0.0]
    err = attTrackingError.attTrackingError()
    err.ModelTag = "attTrackingError"
    err.attNavInMsg.subscribeTo(nav.attOutMsg)
    err.attRefInMsg.subscribeTo(ref.attRefOutMsg)
    ctl = mrpFeedback.mrpFeedback()
    ctl.ModelTag = "mrpFeedback"
    ctl.guidInMsg.subscribeTo(err.attGuidOutMsg)
    ctl.K = K_MRP
    ctl.P = P_MRP
    ctl.Ki = -1.0  # no integral term
    veh = messaging.VehicleConfigMsgPayload()
    veh.ISCPntB_B = [x for row in sc.hub.IHubPntBc_B for x in row]
    veh_msg = messaging.VehicleConfigMsg().write(veh)
    ctl.vehConfigInMsg.subscribeTo(veh_msg)
    fswSetupRW.clearSetup()
    for w in wheels:
        fswSetupRW.create(w["axis"], w["inertia"], w.get("max_torque", 1.0))
    rw_params = fswSetupRW.writeConfigMessage()
    mot = rwMotorTorque.rwMotorTorque()
    mot.ModelTag = "rwMotorTorque"
    mot.controlAxes_B = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    mot.vehControlInMsg.subscribeTo(ctl.cmdTorqueOutMsg)
    mot.rwParamsInMsg.subscribeTo(rw_params)
    rw.rwMotorCmdInMsg.subscribeTo(mot.rwMotorTorqueOutMsg)
    for m in (nav, ref, err, ctl, mot):
        sim.AddModelToTask("fswTask", m)
    keep += [nav, ref, err, ctl, mot, veh, veh_msg, rw_params]

    sim.defer = False
    sim.ConfigureStopTime(macros.sec2nano(duration))
    sim._fsw_mc_keep = keep
    return sim, rec


def bsk_run(duration, omega0):
    """One Monte Carlo run as the Controller does it (create, initialise, execute); the final
    pointing error (arcsec)."""
    sim, rec = bsk_build(duration, omega0)
    sim.InitializeSimulation()
    sim.ExecuteSimulation()
    sigma = np.array(rec.sigma_BN[-1])
    return math.degrees(4.0 * math.atan(float(np.linalg.norm(sigma)))) * 3600.0


def bsk_runs(duration, omegas):
    return [bsk_run(duration, w) for w in omegas]


# --- The benchmark ---------------------------------------------------------------------------


def timed(f, *args):
    t0 = time.perf_counter()
    out = f(*args)
    return time.perf_counter() - t0, out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--duration", type=float, default=600.0)
    ap.add_argument("--cores", type=int, default=os.cpu_count())
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", type=Path)
    ap.add_argument("--check-arcsec", type=float, default=300.0,
                    help="largest pointing error Basilisk may end with (runs of 300 s or more)")
    ap.add_argument("--plain-loop", action="store_true",
                    help="(b), (c) with the plain Simulation loop even if the campaign API exists")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        worker_main(args.worker, args.duration, args.runs, args.seed)
        return

    import satsim

    n, dur = args.runs, args.duration
    ticks = round(dur / PERIOD)
    omegas = draws(n, args.seed)
    # The factories from the module `fsw_mc` (not `__main__`), so that worker processes
    # can import them whatever their start method.
    if str(HERE) not in sys.path:
        sys.path.insert(0, str(HERE))
    import fsw_mc

    why, api = (("--plain-loop given", False) if args.plain_loop
                else campaign_api(fsw_mc.make_idle))
    print(f"{n} runs of {dur:g} s ({ticks} ticks of {PERIOD} s each), {args.rounds} rounds, "
          f"satsim {getattr(satsim, '__version__', '?')}; (b)-(d) through "
          + ("satsim.campaign(controller=...)" if api else
             f"the fallback, a plain satsim.Simulation loop per run ({why})"))
    from Basilisk import __version__ as bsk_version

    print(f"Basilisk {bsk_version}: mrpFeedback K = {K_MRP:g} N m, P = {P_MRP:g} N m s "
          f"(satsim law kp = {KP:g} N m/rad on 2 q_xyz, kd = {KD:g} N m s/rad)")

    def sat_law():
        return (satsim_campaign(dur, n, fsw_mc.make_fsw, None) if api
                else satsim_loops(dur, omegas, Fsw()))

    def sat_idle():
        return (satsim_campaign(dur, n, fsw_mc.make_idle, None) if api
                else satsim_loops(dur, omegas, Idle()))

    cases = {
        "basilisk": lambda: bsk_runs(dur, omegas),
        "satsim_law": sat_law,
        "satsim_idle": sat_idle,
        "run_no_control": lambda: satsim_runs(dur, omegas, controller=False),
        "run_builtin": lambda: satsim_runs(dur, omegas, controller=True),
    }
    if api:
        cases["campaign_all_cores"] = lambda: satsim_campaign(dur, n, fsw_mc.make_fsw,
                                                                 args.cores)
        cases["processes_all_cores"] = lambda: processes(dur, n, args.cores, args.seed)
    times = {k: [] for k in cases}
    errors = {}
    load_start = os.getloadavg()
    for rnd in range(args.rounds):
        order = list(cases) if rnd % 2 == 0 else list(cases)[::-1]
        for k in order:
            t, out = timed(cases[k])
            times[k].append(t)
            if isinstance(out, list):
                errors[k] = out
        print(f"round {rnd + 1}: " + ", ".join(f"{k} {times[k][-1]:.2f} s" for k in cases),
              flush=True)

    med = {k: statistics.median(v) for k, v in times.items()}
    res = {"runs": n, "duration_s": dur, "ticks_per_run": ticks, "rounds": args.rounds,
           "api": "campaign" if api else "fallback", "fallback_reason": why or None,
           "basilisk_version": bsk_version,
           "gains": {"kp": KP, "kd": KD, "mrpFeedback_K": K_MRP, "mrpFeedback_P": P_MRP},
           "median_s": med, "times_s": times,
           "loadavg_start_end": [load_start, os.getloadavg()]}
    rate = {k: n / med[k] for k in med}
    res["runs_per_core_second"] = {k: rate[k] for k in ("basilisk", "satsim_law")}
    res["satsim_over_basilisk"] = rate["satsim_law"] / rate["basilisk"]
    res["overhead_us_per_tick"] = {
        "empty_controller": (med["satsim_idle"] - med["run_no_control"]) / (n * ticks) * 1e6,
        "example_law": (med["satsim_law"] - med["run_builtin"]) / (n * ticks) * 1e6,
    }
    if api:
        res["all_cores"] = {"cores": args.cores,
                            "campaign_runs_per_s": rate["campaign_all_cores"],
                            "processes_runs_per_s": rate["processes_all_cores"],
                            "campaign_percent_of_processes":
                                100.0 * rate["campaign_all_cores"] / rate["processes_all_cores"],
                            "campaign_percent_per_round": [
                                100.0 * p / c for c, p in zip(times["campaign_all_cores"],
                                                              times["processes_all_cores"])]}
    # The pointing error at the end of the controlled runs (the uncontrolled ones, the
    # {} controller's and the controller-off runs', tumble: they are timing baselines only).
    res["final_pointing_error_arcsec"] = {
        k: {"max": max(errors[k]), "median": statistics.median(errors[k])}
        for k in ("basilisk", "satsim_law", "run_builtin", "campaign_all_cores")
        if errors.get(k)}

    w = 52
    print()
    print(f"{'case (median of ' + str(args.rounds) + ' rounds)':{w}s} {'wall s':>8s} "
          f"{'s/run':>7s} {'runs/core-s':>11s}")
    labels = {
        "basilisk": "(a) Basilisk, C FSW (mrpFeedback + rwMotorTorque)",
        "satsim_law": "(b) satsim, the law in Python at 10 Hz",
        "satsim_idle": "(c) satsim, a Python controller returning {}",
        "run_no_control": "(c) satsim.run, controller off (no Python)",
        "run_builtin": "(c) satsim.run, built-in controller (no Python)",
        "campaign_all_cores": f"(d) satsim.campaign, workers={args.cores}",
        "processes_all_cores": f"(d) {args.cores} processes of the plain loop",
    }
    for k in cases:
        per_core = "" if k in ("campaign_all_cores", "processes_all_cores") else f"{rate[k]:11.2f}"
        print(f"{labels[k]:{w}s} {med[k]:8.3f} {med[k] / n:7.3f} {per_core:>11s}")
    print()
    print(f"load average (1, 5, 15 min) at the start {load_start[0]:.2f} {load_start[1]:.2f} "
          f"{load_start[2]:.2f}, at the end " + " ".join(f"{x:.2f}" for x in os.getloadavg())
          + f" ({os.cpu_count()} cores)")
    print(f"satsim / Basilisk (runs per core-second): {res['satsim_over_basilisk']:.1f}x")
    oh = res["overhead_us_per_tick"]
    print(f"Python overhead per tick: empty controller {oh['empty_controller']:.1f} us, "
          f"example law {oh['example_law']:.1f} us")
    if api:
        a = res["all_cores"]
        print(f"all {a['cores']} cores: campaign {a['campaign_runs_per_s']:.2f} runs/s, "
              f"processes {a['processes_runs_per_s']:.2f} runs/s: "
              f"campaign at {a['campaign_percent_of_processes']:.0f} % of the processes' "
              f"(by round: {', '.join(f'{x:.0f} %' for x in a['campaign_percent_per_round'])})")
    for k, v in res["final_pointing_error_arcsec"].items():
        print(f"pointing error at {dur:g} s, {k}: max {v['max']:.1f} arcsec, "
              f"median {v['median']:.1f} arcsec")
    if not api:
        # The Python law on the truth is the built-in discrete controller (fsw_in_the_loop.py
        # checks the trajectories to 1e-12): the same final errors, run by run.
        d = max(abs(a - b) for a, b in zip(errors["satsim_law"], errors["run_builtin"]))
        print(f"Python law against the built-in controller, final error: max difference "
              f"{d:.1e} arcsec")
    bsk_max = res["final_pointing_error_arcsec"]["basilisk"]["max"]
    res["basilisk_converged"] = converged = dur < 300.0 or bsk_max <= args.check_arcsec
    if dur >= 300.0:
        print(f"Basilisk's closed loop {'converged' if converged else 'did NOT converge'}: "
              f"largest error at {dur:g} s {bsk_max:.1f} arcsec (limit {args.check_arcsec:g})")
    if args.json:
        args.json.write_text(json.dumps(res, indent=2) + "\n")
        print(f"wrote {args.json}")
    if not converged:
        sys.exit(1)


if __name__ == "__main__":
    main()
