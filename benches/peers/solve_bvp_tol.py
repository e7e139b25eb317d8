#!/usr/bin/env python3
"""eyeshell's `solver.tol` against SciPy's solve_bvp at the same tolerance, side by side in
one run (the table "Against SciPy's solve_bvp at a requested tolerance" of docs/guide/accuracy.md).

The shell is the one of tests/fixtures/solve_bvp_reference.py (whose equations, split at
the thickness jump Σ_e = πR0/2, this script imports): the default scene with
material.thickness = "nonuniform", D = 0 and solver.epsilon = 0.1, where solve_bvp
converges (at ε = 1e-3 it does not: see that file). For each tol, both solvers are timed
(the least of `REPEATS` runs; eyeshell's time is its summary.json's wall_seconds, the
solve without process start-up) and their true error is measured at their own nodes (the
values each returns: solve_bvp's sol.y, eyeshell's fields.csv), the largest over κ, α_s,
r, θ, Q, against eyeshell at solver.tol = 1e-12 (Hermite–Simpson, interpolated there),
itself checked against the order-6 Richardson solution at solver.tol = 1e-12 at the
latter's nodes. solve_bvp's tol bounds a relative residual, eyeshell's the estimated
error; so that the two are also compared at equal accuracy, eyeshell is run again with
solver.tol set to the true error solve_bvp reached.

    cargo build --release
    python3 benches/peers/solve_bvp_tol.py [path/to/eyeshell]
"""

import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import solve_bvp

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tests", "fixtures"))
import solve_bvp_reference as ref  # noqa: E402

TOLS = [1e-6, 1e-8]
REPEATS = 3
SCENE = [os.path.join(ROOT, "scenes", "default.toml"),
         "--set", 'material.thickness="nonuniform"', "--set", f"solver.epsilon={ref.EPS}"]


def eyeshell(binary, sets, at=None):
    """Solve; return (fields rows, at rows, summary)."""
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "run")
        cmd = [binary, "solve", *SCENE, "--quiet", "--out", out]
        for s in sets:
            cmd += ["--set", s]
        if at is not None:
            cmd += ["--at", ",".join(repr(float(x)) for x in at)]
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode != 0:
            sys.exit(f"eyeshell {' '.join(sets)}: {done.stderr.strip()}")
        fields = np.loadtxt(os.path.join(out, "fields.csv"), delimiter=",", skiprows=1)
        at_rows = (np.loadtxt(os.path.join(out, "at.csv"), delimiter=",", skiprows=1, ndmin=2)
                   if at is not None else None)
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
    return fields, at_rows, summary


# κ, α_s, r, θ, Q in fields.csv's columns.
FIVE = [2, 3, 4, 5, 6]


def reference_at(binary, x):
    _, at, _ = eyeshell(binary, ["solver.tol=1e-11"], at=x)
    return at[:, FIVE]


def scipy_solve(tol):
    tau = np.linspace(0, 1, 401)
    best, sol = None, None
    for _ in range(REPEATS if tol > 1e-7 else 1):
        start = time.perf_counter()
        sol = solve_bvp(ref.stacked, ref.bc, tau, ref.guess(tau), tol=tol, max_nodes=200000)
        t = time.perf_counter() - start
        best = t if best is None else min(best, t)
    assert sol.success, sol.message
    # Its own nodes on each piece; Σ_e once (from below, as eyeshell's node rows have it).
    xs, ys = [], []
    for k, (lo, hi) in enumerate(ref.PIECES):
        s = lo + sol.x * (hi - lo)
        yy, _ = ref.rows(s, sol.y[5 * k:5 * k + 5], k)
        keep = slice(None) if k == 0 else slice(1, None)
        xs.append(s[keep]), ys.append(yy[:, keep])
    return np.concatenate(xs), np.hstack(ys).T, best, len(sol.x)


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release", "eyeshell")
    rich, _, _ = eyeshell(binary, ["solver.tol=1e-12", "solver.richardson=true"])
    print(f"reference: eyeshell tol 1e-12 against its Richardson solution at the latter's "
          f"{len(rich)} nodes: {np.abs(reference_at(binary, rich[:, 0]) - rich[:, FIVE]).max():.1e}")
    print("| tol | solver | nodes | true error | seconds |")
    print("|---|---|---|---|---|")
    for tol in TOLS:
        x, y, t, n = scipy_solve(tol)
        err = np.abs(y - reference_at(binary, x)).max()
        print(f"| {tol:.0e} | solve_bvp (split at Σ_e) | {n} per piece ({len(x)}) | {err:.2e} | {t:.3f} |",
              flush=True)
        for t in [tol, float(f"{err:.0e}")]:
            times = []
            for _ in range(REPEATS):
                fields, _, summary = eyeshell(binary, [f"solver.tol={t}"])
                times.append(summary["wall_seconds"])
            e = np.abs(fields[:, FIVE] - reference_at(binary, fields[:, 0])).max()
            est = summary["error_estimate"]["overall"]
            print(f"| {tol:.0e} | eyeshell solver.tol = {t:.0e} | {len(fields)} | {e:.2e} "
                  f"(estimate {est:.2e}) | {min(times):.4f} |", flush=True)


if __name__ == "__main__":
    main()
