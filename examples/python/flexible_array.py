"""The deployment with flexible panels against the rigid array, from Python (run it cell by
cell or as `python examples/python/flexible_array.py [OUT_DIR]`).

Runs `examples/flexible_array.toml` (the preprint's satellite deploying three panels that
bend: half of each panel's mass a strip along it, 3 modes, 0.5 % damping) and
`examples/scenes/deploy.toml` (the same deployment with rigid panels of the same mass and
inertia), both with output every 0.01 s (the flexible one with RK4 at 2 ms, every mode
resolved), prints what flexibility changes (latch times, bus
rates, settling, tip deflections, the energy the modes dissipate) and plots the bus rate and
the tip deflections into `OUT_DIR/flexible_array.png` (default `out/python`).

Needs: `pip install "./python[examples]"` (matplotlib).
"""

# %%
import re
import sys
from pathlib import Path

import numpy as np

import satsim

ROOT = Path(__file__).resolve().parents[2]
FLEXIBLE = ROOT / "examples" / "flexible_array.toml"
RIGID = ROOT / "examples" / "scenes" / "deploy.toml"
OUT = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "out" / "python"
EVERY = 0.01  # s: the strips ring at 2 to 30 Hz
SETTLED = 1e-4  # rad/s: the bus rate a payload would call quiet


def run(scene: Path, rk4_step=None) -> "satsim.Trajectory":
    """The scene with its output every EVERY seconds, and with RK4 at `rk4_step` if given (its
    text edited, its folder kept)."""
    text = re.sub(r"(?m)^every = .*$", f"every = {EVERY}", scene.read_text())
    if rk4_step is not None:
        text = re.sub(r'(?m)^method = ".*"$', f'method = "rk4"\nstep = {rk4_step}', text)
    return satsim.run(text, base_dir=scene.parent)


# The flexible scene with RK4 at 2 ms, every mode resolved: its own Radau IIA steps over the
# strips' fastest ringing and damps it (0.14 J of the 19.7 J exchanged, in the energy
# budget), where this comparison wants each panel's bending to the last tenth of a
# millimetre and the budget to close.
flex, rigid = run(FLEXIBLE, rk4_step=0.002), run(RIGID)


def rate(r) -> np.ndarray:
    return np.sqrt(r["omega_x"] ** 2 + r["omega_y"] ** 2 + r["omega_z"] ** 2)


def latched(r, hinge: str) -> float:
    """The first time the hinge sits at its stop with zero rate (latched)."""
    at = np.flatnonzero((np.abs(r["angle_" + hinge]) < 1e-9) & (r["rate_" + hinge] == 0.0))
    return float(r.t[at[0]]) if at.size else float("nan")


def settling(r) -> float:
    """The last time the bus rate exceeds SETTLED."""
    over = np.flatnonzero(rate(r) > SETTLED)
    return float(r.t[over[-1]]) if over.size else 0.0


# %% What flexibility changes.
rows = [
    ("h4 latches (s)", latched(rigid, "h4"), latched(flex, "h4")),
    ("h5 latches (s)", latched(rigid, "h5"), latched(flex, "h5")),
    ("largest bus rate (rad/s)", rate(rigid).max(), rate(flex).max()),
    (f"bus rate below {SETTLED:g} rad/s after (s)", settling(rigid), settling(flex)),
    ("energy dissipated (J)", rigid["energy_dissipated"][-1], flex["energy_dissipated"][-1]),
]
tips = [c for c in flex.columns if c.startswith("tip_")]
for c in tips:
    rows.append((f"largest |{c}| (mm)", 0.0, 1e3 * np.abs(flex[c]).max()))
print(f"{'':40s} {'rigid':>12s} {'flexible':>12s}")
for name, a, b in rows:
    print(f"{name:40s} {a:12.6g} {b:12.6g}")
drift = np.abs(flex["energy_budget"] - flex["energy_budget"][0]).max()
print(f"energy budget drift (flexible): {drift:.3e} J of {flex['total_energy'][0]:.3e} J")

# %% Plot: the bus rate and the tips around the latches.
import matplotlib

matplotlib.use("Agg")  # files only; drop this line in a notebook
import matplotlib.pyplot as plt

fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
ax1.semilogy(rigid.t, rate(rigid), label="rigid panels", lw=1.0)
ax1.semilogy(flex.t, rate(flex), label="flexible panels", lw=0.8)
ax1.axhline(SETTLED, color="grey", ls=":", lw=0.8)
ax1.set_ylabel("|bus rate| (rad/s)")
ax1.legend(fontsize="small")
for c in tips:
    ax2.plot(flex.t, 1e3 * flex[c], label=c, lw=0.8)
ax2.set_ylabel("tip deflection (mm)")
ax2.set_xlabel("t (s)")
ax2.legend(ncol=len(tips), fontsize="small")
fig.suptitle("Deployment: flexible against rigid panels")
fig.tight_layout()
OUT.mkdir(parents=True, exist_ok=True)
fig.savefig(OUT / "flexible_array.png", dpi=110)
print(f"wrote {OUT / 'flexible_array.png'}")
