"""The disturbance budget of a run: per phase, the largest and the RMS magnitude of each
disturbance torque about the centre of mass (columns gg_torque_*, srp_torque_*,
earth_radiation_torque_* with `albedo = true`, drag_torque_*, magnetic_torque_*), and which one
dominates.

    satsim run examples/scenes/deploy_in_orbit.toml --out out/deploy_in_orbit
    python3 examples/python/disturbance_budget.py out/deploy_in_orbit/trajectory.csv 0 3 12 100 600

The numbers after the file are the phases' boundaries (s). Only the standard library.
"""

import csv
import math
import sys

EFFECTS = [("gravity gradient", "gg"), ("solar pressure", "srp"),
           ("Earth's light", "earth_radiation"), ("drag", "drag"), ("magnetic", "magnetic")]


def main(path, bounds):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    present = [(label, key) for label, key in EFFECTS if f"{key}_torque_x" in rows[0]]
    print("| phase (s) | sunlight | " + " | ".join(f"{l}: max / RMS (N m)" for l, _ in present)
          + " | dominant |")
    print("|---" * (len(present) + 3) + "|")
    for a, b in zip(bounds, bounds[1:]):
        phase = [r for r in rows if a <= float(r["t"]) <= b]
        cells, best = [], (0.0, "")
        for label, key in present:
            mags = [math.sqrt(sum(float(r[f"{key}_torque_{c}"]) ** 2 for c in "xyz"))
                    for r in phase]
            peak = max(mags)
            rms = math.sqrt(sum(m * m for m in mags) / len(mags))
            cells.append(f"{peak:.2e} / {rms:.2e}")
            best = max(best, (rms, label))
        sun = [float(r["shadow"]) for r in phase] if "shadow" in rows[0] else [1.0]
        light = f"{min(sun):.2f} to {max(sun):.2f}"
        print(f"| {a:g} to {b:g} | {light} | " + " | ".join(cells) + f" | {best[1]} |")


if __name__ == "__main__":
    main(sys.argv[1], [float(x) for x in sys.argv[2:]] or [0.0, 1e300])
