"""The same shell by scipy.integrate.solve_bvp and by eyeshell.solve: times and errors.

The loaded, ungrown shell with the non-uniform thickness (docs/MODEL.md §1-4; no fibres,
ε = 0.1: at ε = 1e-3 solve_bvp converges at this tol 1e-6 too, in 638 nodes to 3.4e-10,
but at tol 1e-8 its residual stalls near 1e-8 next to the pole and its mesh runs away, see
tests/fixtures/solve_bvp_reference.py; ε = 0.1 serves both tolerances). solve_bvp needs the shell split by hand at the
thickness jump Σ_e = πR0/2: two pieces mapped to [0, 1], stacked into 10 unknowns, with 5
continuity conditions at the joint. eyeshell takes the scene's keys.
Errors: the first integral Q cos θ + r t_s sin θ − r² ΔP/2, zero for the exact solution
(§3), and r against eyeshell on 32,001 nodes (converged to round-off at order 4).
"""
import time

import numpy as np
from scipy.integrate import solve_bvp

import eyeshell

DP, C, EB, R0, F, EPS = 2.0, 100.0, 18.0, 10.0, 0.8, 0.1
L, SE = np.pi * F * R0, np.pi * R0 / 2
PIECES = [(EPS, SE), (SE, L)]
scene = eyeshell.Scene({"material.thickness": "nonuniform", "solver.epsilon": EPS})

# The cornea's stretch α, from ΔP = 4 C_c H_c / (α R_c)(1 − α⁻⁶) (§2), by bisection.
lo, hi = 1.0, 7 ** (1 / 6)
for _ in range(200):
    mid = (lo + hi) / 2
    lo, hi = (mid, hi) if 4 * C * 0.65 / (mid * R0) * (1 - mid**-6) < DP else (lo, mid)
ALPHA = (lo + hi) / 2


def thickness(s, piece):
    if piece == 0:
        return 0.65 - 0.2 * np.tanh((s - np.pi * R0 / 6) / 1.5)
    return 0.475 + 0.025 * np.tanh(s - 0.7 * np.pi * R0)


def stretches(s, y, piece):
    """α_s from t_s = 2ζC(α_s/α_φ − (α_s α_φ)⁻³) by Newton, and t_φ."""
    kappa, r, theta, q, ts = y
    zeta, aphi = thickness(s, piece), r / (R0 * np.sin(s / R0))
    a = np.array(aphi, dtype=float)
    for _ in range(60):
        a = a - (a / aphi - (a * aphi) ** -3 - ts / (2 * zeta * C)) / (1 / aphi + 3 * a**-4 * aphi**-3)
    return a, 2 * zeta * C * (aphi / a - (a * aphi) ** -3)


def rhs(s, y, piece):
    kappa, r, theta, q, ts = y
    a, tphi = stretches(s, y, piece)
    c, sn = np.cos(theta), np.sin(theta)
    return np.vstack([a * ((sn / r - kappa) * c / r - q / (r * EB)), a * c, a * kappa,
                      a * (r * DP - kappa * r * ts - sn * tphi), (a / r) * (kappa * q + (tphi - ts) * c)])


def stacked(tau, Y):
    return np.vstack([(b - a) * rhs(a + tau * (b - a), Y[5 * k:5 * k + 5], k) for k, (a, b) in enumerate(PIECES)])


def bc(Ya, Yb):
    kappa, r, theta, q, ts = Ya[:5]
    a = stretches(np.array([EPS]), Ya[:5].reshape(5, 1), 0)[0][0]
    pole = [r - EPS * a, theta - EPS * a * kappa, q * np.cos(theta) + r * ts * np.sin(theta) - r * r * DP / 2]
    cornea = [Yb[6] - ALPHA * R0 * np.sin(L / R0), Yb[7] - L / R0]
    return np.array(pole + cornea + list(Yb[:5] - Ya[5:]))


def guess(tau):  # the uniformly inflated sphere (§7)
    s = [a + tau * (b - a) for a, b in PIECES]
    return np.vstack([row for x in s for row in (np.full_like(x, 1 / (ALPHA * R0)), ALPHA * R0 * np.sin(x / R0),
                      x / R0, 0 * x, np.full_like(x, 2 * 0.65 * C * (1 - ALPHA**-6)))])


def first_integral(r, theta, q, ts):
    return np.abs(q * np.cos(theta) + r * ts * np.sin(theta) - r * r * DP / 2).max()


reference = eyeshell.solve(scene, **{"solver.nodes": 32001})

start = time.perf_counter()
tau = np.linspace(0, 1, 101)
bvp = solve_bvp(stacked, bc, tau, guess(tau), tol=1e-6, max_nodes=100000)
scipy_seconds = time.perf_counter() - start
assert bvp.success, bvp.message
scipy_fi, scipy_r = 0.0, 0.0
for k, (a, b) in enumerate(PIECES):
    s = a + bvp.x * (b - a)
    kappa, r, theta, q, ts = bvp.y[5 * k:5 * k + 5]
    scipy_fi = max(scipy_fi, first_integral(r, theta, q, ts))
    scipy_r = max(scipy_r, np.abs(r - reference.at(s)["r"]).max())

start = time.perf_counter()
sol = eyeshell.solve(scene, **{"solver.nodes": 1001})
eyeshell_seconds = time.perf_counter() - start
eyeshell_fi = first_integral(sol.r, sol.theta, sol.Q, sol.t_s)
eyeshell_r = np.abs(sol.r - reference.at(sol.Sigma)["r"]).max()

print(f"{'':22}{'time':>10}{'nodes':>8}{'first integral':>16}{'max |r − r_ref|':>17}")
print(f"{'scipy solve_bvp 1e-6':22}{scipy_seconds:>9.3f}s{2 * len(bvp.x):>8}{scipy_fi:>16.1e}{scipy_r:>17.1e}")
print(f"{'eyeshell.solve':22}{eyeshell_seconds:>9.3f}s{len(sol):>8}{eyeshell_fi:>16.1e}{eyeshell_r:>17.1e}")
