"""Radau IIA against the BDF family on the flexible deployment's ringing, as a model problem:
why `examples/flexible_array.toml` runs Radau IIA and not a BDF code (CVODE's, LSODA's).

The model: the strips' three clamped modes (1.77, 11.1 and 32.9 Hz, 0.5 % damping) released
from a static deflection, 20 s, the time the first mode rings after each latch of the
deployment. As in the scene (`elastic_error = false`), only the slow ringing is held to the
tolerance: the first mode's displacement and rate, through which the ringing reaches the
hinge rates; the two stiff modes are left out of the error (a huge `atol`), for the method
to step over. The error is the first mode's displacement against the exact solution (the
matrix exponential) at 201 times. The same with the first mode alone and the first two: the
stiff modes, not the ringing, hold BDF's steps. Last, BDF's steps at each order. scipy's `Radau` is Hairer's RADAU5, as satsim's; `BDF`
is Shampine & Reichelt's NDF of orders 1 to 5; `LSODA` switches between Adams and BDF. The
Jacobian is given exactly, so `nfev` counts the right-hand sides of the steps and the
Newton iterations only; a finite-difference Jacobian costs one more a state (47 on the
scene) each time `njev` counts one.

    python benches/accuracy/ringing_methods.py

Not run by cargo or CI. Needs numpy and scipy.
"""

from collections import Counter

import numpy as np
from scipy.integrate import BDF, solve_ivp
from scipy.linalg import expm

FREQUENCIES_HZ = np.array([1.77, 11.1, 32.9])
DAMPING = 0.005
DEFLECTION = np.array([1.0, 0.3, 0.1]) * 1e-2  # modal coordinates at the release
DURATION = 20.0


def model(modes=len(FREQUENCIES_HZ)):
    """`y' = A y` of the first `modes` modes, and the state at the release."""
    w = 2 * np.pi * FREQUENCIES_HZ[:modes]
    n = len(w)
    a = np.zeros((2 * n, 2 * n))
    for i in range(n):
        a[i, n + i] = 1.0
        a[n + i, i] = -w[i] ** 2
        a[n + i, n + i] = -2 * DAMPING * w[i]
    return a, np.concatenate([DEFLECTION[:modes], np.zeros(n)])


def held(modes, tol):
    """The error's weights: the first mode's displacement and rate at `tol`, the rest out."""
    atol = np.full(2 * modes, 1e3)
    atol[[0, modes]] = tol
    return atol


def bdf_orders(modes, tol):
    """How many of BDF's steps over the run with the first `modes` modes were of each order."""
    a, y0 = model(modes)
    atol = held(modes, tol)
    s = BDF(lambda t, y: a @ y, 0.0, y0, DURATION, rtol=tol, atol=atol, jac=lambda t, y: a)
    orders = Counter()
    while s.status == "running":
        s.step()
        orders[int(s.order)] += 1
    return dict(sorted(orders.items()))


def main():
    times = np.linspace(0.0, DURATION, 201)
    print("modes  method  tol     error (first mode)  steps  nfev    njev  nlu")
    for modes in range(1, len(FREQUENCIES_HZ) + 1):
        a, y0 = model(modes)
        exact = np.array([expm(a * t) @ y0 for t in times])[:, 0]
        for method in ("Radau", "BDF", "LSODA"):
            for tol in (1e-4, 1e-5, 1e-6, 1e-7):
                s = solve_ivp(
                    lambda t, y: a @ y,
                    (0.0, DURATION),
                    y0,
                    method=method,
                    rtol=tol,
                    atol=held(modes, tol),
                    jac=lambda t, y: a,
                    dense_output=True,
                )
                error = np.abs(s.sol(times)[0] - exact).max()
                print(
                    f"{modes:5d}  {method:6s}  {tol:.0e}  {error:18.2e}  {len(s.t) - 1:5d}  "
                    f"{s.nfev:6d}  {s.njev:4d}  {s.nlu:4d}"
                )
    print("\nBDF's steps at each order, tol 1e-5")
    for modes in range(1, len(FREQUENCIES_HZ) + 1):
        print(f"{modes} mode(s), {FREQUENCIES_HZ[modes - 1]} Hz the highest: {bdf_orders(modes, 1e-5)}")


if __name__ == "__main__":
    main()
