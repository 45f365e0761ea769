"""Deployment of the solar array, from Python (a notebook in a script: run it cell by cell
or as `python examples/python/deploy.py`).

Runs `examples/scenes/deploy.toml` (the preprint's satellite opening its three folded panels
on hinge springs, latching at the stops, with reaction wheels holding the bus), plots the
hinge angles and the bus rates with matplotlib into `out/python/deploy.png` (or the folder
given as the first argument), and prints the structural modes of the stowed configuration.

Needs: `pip install "./python[examples]"` (matplotlib; pandas and Dask come with it).
"""

# %%
import sys
from pathlib import Path

import numpy as np

import satsim

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "examples" / "scenes" / "deploy.toml"
OUT = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "out" / "python"

# %% Run the scene: nothing is written to disk, the trajectory is in memory.
r = satsim.run(SCENE)
print(r)
hinges = [c[len("angle_"):] for c in r.columns if c.startswith("angle_")]
print("hinges:", ", ".join(hinges))
print(f"final angles (deg): "
      + ", ".join(f"{h} {np.degrees(r['angle_' + h][-1]):+.2f}" for h in hinges))
print(f"largest bus rate: {np.abs(r.data[:, [r.columns.index(c) for c in ('omega_x', 'omega_y', 'omega_z')]]).max():.3e} rad/s")

# %% Plot the hinge angles and the bus rates.
import matplotlib

matplotlib.use("Agg")  # files only; drop this line in a notebook
import matplotlib.pyplot as plt

fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
for h in hinges:
    ax1.plot(r.t, np.degrees(r["angle_" + h]), label=h)
ax1.set_ylabel("hinge angle (deg)")
ax1.legend(ncol=len(hinges), fontsize="small")
for c in ("omega_x", "omega_y", "omega_z"):
    ax2.plot(r.t, np.degrees(r[c]), label=c)
ax2.set_ylabel("bus rate (deg/s)")
ax2.set_xlabel("t (s)")
ax2.legend(ncol=3, fontsize="small")
fig.suptitle("Deployment of the solar array")
fig.tight_layout()
OUT.mkdir(parents=True, exist_ok=True)
fig.savefig(OUT / "deploy.png", dpi=120)
print(f"wrote {OUT / 'deploy.png'}")

# %% The structural modes at the initial state (contract section 9): the stowed array on its
# springs, the wheels and the attitude controller included.
modes = satsim.modes(SCENE)
print(f"modes at t = 0: {modes['rigid_modes']} rigid")
for mode in modes["modes"]:
    largest = max(mode["shape"], key=lambda k: abs(mode["shape"][k]) if k.startswith("angle_") else 0)
    print(f"  {mode['frequency_hz']:10.4f} Hz   damping ratio {mode['damping_ratio']:.4f}   "
          f"mostly {largest}")
