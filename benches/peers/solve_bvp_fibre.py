#!/usr/bin/env python3
"""The bvp4c-style peer, side by side with eyeshell (issue 15): the non-uniform fibre shell
(docs/MODEL.md §§2-4: thickness H(Σ) with its jump at Σ_e = πR0/2, fibres D = 200 kPa with
the angle ψ(Σ), whose kinks are at a = Σ_e/20, b = Σ_e/4 and Σ_e), loaded, ungrown, at the
default pole truncation ε = 1e-3.

SciPy's solve_bvp (a 4th-order collocation with residual control, bvp4c's scheme) is split
at the three breakpoints by hand, as a user must: unsplit it refines at the thickness jump
for ever (docs/MODEL.md §4). Each piece is mapped to τ ∈ [0, 1] and the four are stacked
into one system of 20 unknowns (κ, r, θ, Q, t_s per piece): 3 conditions at the pole, 2 at
the cornea, 5 of continuity at each of the 3 joints. t_s is an unknown, α_s comes from the
constitutive law at each point (monotone in α_s; safeguarded Newton), so no derivative of
H or ψ is needed and the jump conditions are automatic. Its Jacobian is SciPy's own finite
differences (solve_bvp's default: what a user gets without writing one).

eyeshell solves the same shell (scenes/fibres-nonuniform.toml) with Hermite-Simpson at
N = 801 (+ breakpoint and pole nodes), KINSOL and the block LU, cold (from the inflated
sphere, as solve_bvp starts). Both are timed inside their own process (solve_bvp with
perf_counter around the call; eyeshell's summary.json `wall_seconds`, mesh to fields), in
this one run, best of several repetitions each.

The error of both: against eyeshell at N = 12801 (its order 4 is observed on this shell by
`eyeshell converge`; at 12801 its error is below 1e-11 relative), at 400 points inside each
piece, through each solver's own continuous interpolant (solve_bvp's `sol.sol`, eyeshell's
`--at`). Reported per field (κ, α_s, r, θ, Q) as the largest absolute error and relative to
the field's largest magnitude.

    python3 benches/peers/solve_bvp_fibre.py [--eyeshell target/release/eyeshell] [--tol 1e-6]

tests/cli/peer.rs runs it once (one repetition each) and checks the errors, not the times.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import solve_bvp

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The cornea's stretch and H(Σ), as the fixture for `eyeshell compare` computes them.
sys.path.insert(0, os.path.join(ROOT, "tests", "fixtures"))
import solve_bvp_reference as ref  # noqa: E402
SCENE = os.path.join(ROOT, "scenes", "fibres-nonuniform.toml")

DP, C, D, EB, R0, F, EPS = 2.0, 100.0, 200.0, 18.0, 10.0, 0.8, 1e-3
CC, HC, RC = 100.0, 0.65, 10.0
L = np.pi * F * R0
SE = np.pi * R0 / 2
B = SE / 4
A = B / 5
PIECES = [(EPS, A), (A, B), (B, SE), (SE, L)]
FIELDS = ["kappa", "alpha_s", "r", "theta", "Q"]


ALPHA = ref.cornea_alpha()
THETA_STAR = L / RC
R_STAR = ALPHA * RC * np.sin(L / RC)


def thickness(s, piece):
    """H(Σ), §4: the reference's first formula up to Σ_e (pieces 0-2), its second beyond."""
    return ref.thickness(s, 0 if piece < 3 else 1)


def psi(s, piece):
    """The fibre angle ψ(Σ), §4 (with the misprint fixed: 0.05 in the third piece)."""
    if piece == 0:
        return np.full_like(s, 0.25 * np.pi)
    if piece == 1:
        return np.pi * (0.25 + 0.06 * np.cos(np.pi * (s - A) / (B - A)) - 0.06)
    if piece == 2:
        return np.pi * (0.25 + 0.05 - 0.17 * np.cos(np.pi * (s - B) / (SE - B)))
    return np.pi * (0.25 + 0.22 * np.cos(np.pi * (s - SE) / (L - SE)))


def tensions(a, aphi, zeta, s2, c2):
    """t_s, t_φ and ∂t_s/∂α_s of the reinforced neo-Hookean law (§2)."""
    i4 = a * a * s2 + aphi * aphi * c2 - 1
    on = i4 > 0
    fib = np.where(on, i4, 0.0)
    iso = (a * aphi) ** -3
    ts = 2 * zeta * (C * (a / aphi - iso) + D * fib * (a / aphi) * s2)
    tphi = 2 * zeta * (C * (aphi / a - iso) + D * fib * (aphi / a) * c2)
    dts = 2 * zeta * (C * (1 / aphi + 3 * iso / a)
                      + D * s2 * (fib / aphi + np.where(on, 2 * a * a * s2 / aphi, 0.0)))
    return ts, tphi, dts


def alpha_s_of(ts, zeta, aphi, s2, c2):
    """α_s with t_s(α_s) = ts: t_s is increasing in α_s, so Newton, kept inside a bracket
    that every iterate narrows (bisection when a step leaves it: the fibre term's kink)."""
    a = np.array(aphi, dtype=float)
    lo = np.full_like(a, 1e-3)
    hi = np.full_like(a, 1e3)
    for _ in range(100):
        f, _, df = tensions(a, aphi, zeta, s2, c2)
        f = f - ts
        lo = np.where(f < 0, a, lo)
        hi = np.where(f > 0, a, hi)
        new = a - f / df
        new = np.where((new > lo) & (new < hi), new, 0.5 * (lo + hi))
        if np.max(np.abs(new - a) / a) < 1e-15:
            return new
        a = new
    return a


def fields(s, y, piece):
    kappa, r, theta, q, ts = y
    rho = R0 * np.sin(s / R0)
    zeta = thickness(s, piece)
    p = psi(s, piece)
    s2, c2 = np.sin(p) ** 2, np.cos(p) ** 2
    aphi = r / rho
    a = alpha_s_of(ts, zeta, aphi, s2, c2)
    _, tphi, _ = tensions(a, aphi, zeta, s2, c2)
    return a, tphi


def rhs(s, y, piece):
    """§3's equations in Σ (ungrown: σ = Σ)."""
    kappa, r, theta, q, ts = y
    a, tphi = fields(s, y, piece)
    c, sn = np.cos(theta), np.sin(theta)
    return np.vstack([
        a * ((sn / r - kappa) * c / r - q / (r * EB)),
        a * c,
        a * kappa,
        a * (r * DP - kappa * r * ts - sn * tphi),
        (a / r) * (kappa * q + (tphi - ts) * c),
    ])


def stacked(tau, Y):
    return np.vstack([(hi - lo) * rhs(lo + tau * (hi - lo), Y[5 * k:5 * k + 5], k)
                      for k, (lo, hi) in enumerate(PIECES)])


def bc(Ya, Yb):
    kappa, r, theta, q, ts = Ya[:5]
    a = fields(np.array([EPS]), Ya[:5].reshape(5, 1), 0)[0][0]
    pole = [r - EPS * a, theta - EPS * a * kappa,
            q * np.cos(theta) + r * ts * np.sin(theta) - r * r * DP / 2]
    cornea = [Yb[16] - R_STAR, Yb[17] - THETA_STAR]
    joints = [Yb[5 * k:5 * k + 5] - Ya[5 * k + 5:5 * k + 10] for k in range(3)]
    return np.concatenate([pole, cornea] + joints)


def guess(tau):
    """The uniformly inflated sphere (§7), eyeshell's own cold start."""
    out = []
    for lo, hi in PIECES:
        s = lo + tau * (hi - lo)
        out += [np.full_like(s, 1 / (ALPHA * R0)), ALPHA * R0 * np.sin(s / R0), s / R0,
                np.zeros_like(s), np.full_like(s, 2 * 0.65 * C * (1 - ALPHA ** -6))]
    return np.vstack(out)


def check_points():
    """400 points strictly inside each piece, the pieces in order."""
    t = (np.arange(400) + 0.5) / 400
    return t, [lo + t * (hi - lo) for lo, hi in PIECES]


def scipy_fields(sol):
    t, ss = check_points()
    Y = sol.sol(t)
    out = []
    for k, s in enumerate(ss):
        y = Y[5 * k:5 * k + 5]
        a, _ = fields(s, y, k)
        out.append(np.vstack([y[0], a, y[1], y[2], y[3]]))
    return np.hstack(out)


def run_scipy(tol, repeats):
    tau = np.linspace(0, 1, 101)
    best, sol = np.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        sol = solve_bvp(stacked, bc, tau, guess(tau), tol=tol, max_nodes=1_000_000)
        best = min(best, time.perf_counter() - start)
        if not sol.success:
            sys.exit(f"solve_bvp failed at tol {tol}: {sol.message}")
    return best, sol


def run_eyeshell(binary, nodes, repeats, at):
    """eyeshell solve at `nodes`, `repeats` times; (best wall_seconds, fields at `at`, mesh nodes)."""
    best, rows, total = np.inf, None, None
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(repeats):
            out = os.path.join(tmp, f"run{i}")
            subprocess.run([binary, "solve", SCENE, "--out", out, "--quiet",
                            "--set", f"solver.nodes={nodes}",
                            "--at", ",".join(repr(float(x)) for x in at)], check=True)
            with open(os.path.join(out, "summary.json")) as f:
                summary = json.load(f)
            best = min(best, summary["wall_seconds"])
            total = summary["nodes"]
            if rows is None:
                data = np.genfromtxt(os.path.join(out, "at.csv"), delimiter=",", names=True)
                rows = np.vstack([data[name] for name in FIELDS])
    return best, rows, total


def errors(fields, ref):
    absolute = np.max(np.abs(fields - ref), axis=1)
    relative = absolute / np.max(np.abs(ref), axis=1)
    return absolute, relative


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--eyeshell", default=os.path.join(ROOT, "target", "release", "eyeshell"))
    parser.add_argument("--tol", type=float, default=1e-6)
    parser.add_argument("--nodes", default="801,1001", help="eyeshell's N, comma-separated")
    parser.add_argument("--repeats", type=int, default=20, help="eyeshell repetitions")
    parser.add_argument("--scipy-repeats", type=int, default=3)
    parser.add_argument("--json", action="store_true", help="print the numbers as JSON")
    args = parser.parse_args()

    at = np.concatenate(check_points()[1])
    _, ref, ref_nodes = run_eyeshell(args.eyeshell, 12801, 1, at)
    _, finer, _ = run_eyeshell(args.eyeshell, 25601, 1, at)
    runs = []
    t_sp, sol = run_scipy(args.tol, args.scipy_repeats)
    runs.append((f"scipy solve_bvp tol {args.tol:g}", t_sp, len(sol.x) * 4, scipy_fields(sol)))
    for n in map(int, args.nodes.split(",")):
        t, y, total = run_eyeshell(args.eyeshell, n, args.repeats, at)
        runs.append((f"eyeshell HS N = {n}", t, total, y))

    if args.json:
        report = {"reference_vs_finer": errors(finer, ref)[1].tolist(), "runs": []}
        for name, t, n, y in runs:
            absolute, relative = errors(y, ref)
            report["runs"].append({"name": name, "seconds": t, "nodes": n,
                                   "absolute": absolute.tolist(), "relative": relative.tolist()})
        print(json.dumps(report))
        return
    print(f"non-uniform fibre shell, D = {D:g}, ε = {EPS:g}; reference: eyeshell HS at {ref_nodes} nodes")
    print(f"{'solver':<34} {'nodes':>7} {'seconds':>10} " + " ".join(f"{f:>9}" for f in FIELDS) + "   max rel")
    for name, t, n, y in runs:
        absolute, relative = errors(y, ref)
        print(f"{name:<34} {n:>7} {t:>10.4g} " + " ".join(f"{e:>9.2e}" for e in absolute)
              + f"   {relative.max():.2e}")
    absolute, relative = errors(finer, ref)
    print(f"{'(reference vs N = 25601)':<34} {'':>7} {'':>10} "
          + " ".join(f"{e:>9.2e}" for e in absolute) + f"   {relative.max():.2e}")
    print(f"solve_bvp: {len(sol.x)} nodes per piece, {sol.niter} iterations, "
          f"max rms residual {sol.rms_residuals.max():.1e}")
    for name, t, _, _ in runs[1:]:
        print(f"speed-up of {name}: {t_sp / t:.0f}x")


if __name__ == "__main__":
    main()
