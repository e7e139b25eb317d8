#!/usr/bin/env python3
"""The published method (the paper's MATLAB code, /work/shared/MODEL.md §9 and docs/MODEL.md
§§3, 5, 6, 8-9) on the const scene, timed beside eyeshell's `solver.tol` in the same run:
the issue-33 must-show "1000× faster at 100× the accuracy".

The published method, as §9 describes it: 501 material points Σ_i uniform on [ε, L]; at
each of 200 explicit Euler steps (Δt = 0.005 to t = 1), the equilibrium BVP in σ is solved
by a bvp4c-style collocation at RelTol = AbsTol = 1e-6 (SciPy's solve_bvp, its stand-in in
benches/peers, with its default finite-difference Jacobian), with α_s an unknown whose
equation is t_s's by the chain rule (the published route: it needs dρ/dσ, taken by
`gradient` at the material points and spline-interpolated, as is ρ); the solution is
evaluated at the material points; z = cumtrapz(σ, −α_s sin θ), shifted so that z at the
cornea junction is the cornea's z*; the retina, the depth d behind the blue surface and g_v
(§6; beyond φ_max the depth where φ = φ_max, interpolated linearly between the straddling
points: the model's mesh-independent rule, not the MATLAB code's last masked point);
then ρ += Δt η [r − ρ]⁺ and σ += Δt (cumtrapz(σ, η [α_s − 1]⁺) + σ_ε η_ε [α_s,ε − 1]⁺).
Each solve starts from the previous step's solution (a warm start, the peer's best case).

The const scene is uniform (ζ = H0, D = 0), so no ζ' or ψ terms are needed; this script
solves that scene only.

Printed: the peer's error, the largest over the output times 0.1, 0.2, 0.4 and 1 of the
axial length and the equatorial radius (the largest r_ret), against eyeshell's reference
(IDA, N = 3201, rtol 1e-10, atol 1e-12: the reference of benches/growth_tol.py), its wall
time (perf_counter around the 200 steps);
then eyeshell `grow scenes/const.toml --set solver.tol=TOL` (TOL = the peer's error / 100
unless --tol is given), its delivered error and its time twice: the subprocess's wall
time (process start, the tolerance rounds, writing the run directory) and summary.json's
`wall_seconds` (the solve with the tolerance rounds, without start-up), and the CPU
seconds of both (the peer's process_time, eyeshell's process's user + system time: on a
shared machine the fairer measure), each the least of --repeat runs; and the ratios.

    cargo build --release
    python3 benches/peers/published_growth.py [--eyeshell target/release/eyeshell]
        [--tol 1.8e-4] [--repeat 5] [--json]
"""

import argparse
import csv
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import cumulative_trapezoid, solve_bvp
from scipy.interpolate import CubicSpline

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE = os.path.join(ROOT, "scenes", "const.toml")

# §8's defaults, the const scene.
DP, C, EB, H0, R0, F, EPS = 2.0, 100.0, 18.0, 0.65, 10.0, 0.8, 1e-3
CC, HC, RC = 100.0, 0.65, 10.0
ETA0, GAMMA, DELTA = 70.0, 8.0, 4.0
POINTS, STEPS, T_END, BVP_TOL = 501, 200, 1.0, 1e-6
# §6: the blue best-focus surface.
P1, P2, P3 = -4.464456500210127, -8.019851138753314, 23.6349728997666
Z_B, PHI_MAX = -0.5064886748669879, 0.5870000878571975

L = np.pi * F * R0


def cornea_alpha():
    """ΔP = 4 C_c H_c / (α R_c) (1 − α⁻⁶) on (1, 7^(1/6)), by bisection (§3)."""
    lo, hi = 1.0, 7 ** (1 / 6)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if 4 * CC * HC / (mid * RC) * (1 - mid ** -6) < DP:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


ALPHA = cornea_alpha()
THETA_STAR = L / RC
R_STAR = ALPHA * RC * np.sin(L / RC)
Z_STAR = ALPHA * RC * (1 + np.cos(L / RC))


class Shell:
    """The grown, unloaded shell's data as functions of σ: ρ and dρ/dσ, splines through
    the material points (dρ/dσ by `gradient` first, as the published code does)."""

    def __init__(self, sigma, rho):
        self.rho = CubicSpline(sigma, rho)
        self.drho = CubicSpline(sigma, np.gradient(rho, sigma))

    def rhs(self, s, y):
        kappa, r, theta, q, a = y
        rho, drho = self.rho(s), self.drho(s)
        aphi = r / rho
        iso = (a * aphi) ** -3
        ts = 2 * H0 * C * (a / aphi - iso)
        tphi = 2 * H0 * C * (aphi / a - iso)
        c, sn = np.cos(theta), np.sin(theta)
        dr = a * c
        dts = (a / r) * (kappa * q + (tphi - ts) * c)
        # t_s(α_s, α_φ) by the chain rule (ζ' = 0: uniform thickness, ζ = H).
        ts_a = 2 * H0 * C * (1 / aphi + 3 * iso / a)
        ts_phi = 2 * H0 * C * (-a / aphi ** 2 + 3 * iso / aphi)
        daphi = dr / rho - r * drho / rho ** 2
        return np.vstack([
            a * ((sn / r - kappa) * c / r - q / (r * EB)),
            dr,
            a * kappa,
            a * (r * DP - kappa * r * ts - sn * tphi),
            (dts - ts_phi * daphi) / ts_a,
        ])

    def bc(self, ya, yb, s_eps):
        kappa, r, theta, q, a = ya
        aphi = r / self.rho(s_eps)
        ts = 2 * H0 * C * (a / aphi - (a * aphi) ** -3)
        return np.array([
            r - s_eps * a,
            theta - s_eps * a * kappa,
            q * np.cos(theta) + r * ts * np.sin(theta) - r * r * DP / 2,
            yb[1] - R_STAR,
            yb[2] - THETA_STAR,
        ])


def blue(phi):
    return P1 * phi ** 4 + P2 * phi ** 2 + P3


OUTPUT_STEPS = {20: 0.1, 40: 0.2, 80: 0.4, 200: 1.0}  # the const scene's output.times


def stimulus(sigma, kappa, r, theta, a, rho):
    """Retina (§6), axial length, equatorial radius (largest r_ret) and g_v."""
    z = cumulative_trapezoid(-a * np.sin(theta), sigma, initial=0.0)
    z += Z_STAR - z[-1]
    h = H0 / (a * (r / rho))
    z_ret = z - 0.5 * h * np.cos(theta)
    r_ret = r - 0.5 * h * np.sin(theta)
    phi = np.arctan2(r_ret, z_ret - Z_B)
    d = blue(phi) - np.hypot(r_ret, z_ret - Z_B)
    beyond = phi >= PHI_MAX
    if beyond.any():
        k = int(np.argmax(beyond))
        if k > 0:
            w = (PHI_MAX - phi[k - 1]) / (phi[k] - phi[k - 1])
            d[beyond] = (1 - w) * d[k - 1] + w * d[k]
        else:
            d[beyond] = d[0]
    return z_ret[0], r_ret.max(), np.maximum(d, 0.0)


def published():
    """The 200 Euler steps; ({t: (axial length, equatorial radius)} at the output times,
    wall and CPU seconds, collocation iterations, largest mesh)."""
    big_sigma = np.linspace(EPS, L, POINTS)
    g_c = 0.5 * ETA0 * (1 + np.tanh((GAMMA - big_sigma) / DELTA))
    sigma = big_sigma.copy()
    rho = R0 * np.sin(big_sigma / R0)
    # The inflated sphere (§7): the const scene's t = 0 solution, the first guess.
    guess_x = sigma.copy()
    guess_y = np.vstack([np.full_like(sigma, 1 / (ALPHA * R0)), ALPHA * R0 * np.sin(sigma / R0),
                         sigma / R0, np.zeros_like(sigma), np.full_like(sigma, ALPHA)])
    dt = T_END / STEPS
    iterations, largest, outputs = 0, 0, {}
    start, cpu = time.perf_counter(), time.process_time()
    for step in range(STEPS + 1):
        shell = Shell(sigma, rho)
        s_eps = sigma[0]
        sol = solve_bvp(shell.rhs, lambda ya, yb: shell.bc(ya, yb, s_eps), guess_x, guess_y,
                        tol=BVP_TOL, bc_tol=BVP_TOL, max_nodes=10000)
        if not sol.success:
            sys.exit(f"solve_bvp failed at step {step}: {sol.message}")
        iterations += sol.niter
        largest = max(largest, len(sol.x))
        kappa, r, theta, q, a = sol.sol(sigma)
        axial, equator, g_v = stimulus(sigma, kappa, r, theta, a, rho)
        if step in OUTPUT_STEPS:
            outputs[OUTPUT_STEPS[step]] = (axial, equator)
        if step == STEPS:
            break
        eta = g_c * g_v
        grow_s = eta * np.maximum(a - 1, 0.0)
        rho_new = rho + dt * eta * np.maximum(r - rho, 0.0)
        sigma_new = sigma + dt * (cumulative_trapezoid(grow_s, sigma, initial=0.0)
                                  + sigma[0] * grow_s[0])
        # The next solve starts from this one, carried to the new σ by material point.
        guess_x, guess_y = sigma_new, np.vstack([kappa, r, theta, q, a])
        sigma, rho = sigma_new, rho_new
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    return outputs, seconds, cpu, iterations, largest


def eyeshell_grow(binary, sets, out):
    cmd = [binary, "grow", SCENE, "--out", out, "--quiet", "--set", "output.history_points=0"]
    for s in sets:
        cmd += ["--set", s]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    with open(os.path.join(out, "series.csv")) as f:
        rows = {float(r["t"]): (float(r["axial_length"]), float(r["equatorial_radius"]))
                for r in csv.DictReader(f)}
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    return rows, wall, summary, cpu


def error(rows, ref):
    """The largest error of the axial length and the equatorial radius over the output
    times of `rows` (mm), and the time where it is."""
    return max((max(abs(rows[t][0] - ref[t][0]), abs(rows[t][1] - ref[t][1])), t)
               for t in rows if t > 0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--eyeshell", default=os.path.join(
        os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release", "eyeshell"))
    ap.add_argument("--tol", type=float, default=None,
                    help="eyeshell's solver.tol (default: the peer's error / 100)")
    ap.add_argument("--repeat", type=int, default=5, help="eyeshell repetitions")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        ref, _, _, _ = eyeshell_grow(
            a.eyeshell, ["solver.nodes=3201", "solver.rtol=1e-10", "solver.atol=1e-12"],
            os.path.join(tmp, "ref"))
        peer, peer_s, peer_cpu, iterations, largest = published()
        peer_err, peer_t = error(peer, ref)
        tol = a.tol if a.tol is not None else float(f"{peer_err / 100:.1e}")
        runs = [eyeshell_grow(a.eyeshell, [f"solver.tol={tol}"], os.path.join(tmp, f"r{i}"))
                for i in range(a.repeat)]
        rows, _, summary, _ = runs[0]
        es_err, es_t = error(rows, ref)
        wall = min(r[1] for r in runs)
        inside = min(r[2]["wall_seconds"] for r in runs)
        es_cpu = min(r[3] for r in runs)
        # A round's runs go on two threads: on two idle cores the process takes its CPU
        # seconds less the cheaper thread of every round, and the solve (no start-up, no
        # output) the dearer thread of every round.
        rounds = [r[2].get("accuracy", {}).get("rounds", []) for r in runs]
        critical = min(r[3] - sum(min(x["delivered_cpu_seconds"], x["companions_cpu_seconds"]) for x in rs)
                       for r, rs in zip(runs, rounds))
        threads = min(sum(max(x["delivered_cpu_seconds"], x["companions_cpu_seconds"]) for x in rs)
                      for rs in rounds)
        load = os.getloadavg()
        accuracy = summary.get("accuracy", {})
    report = {
        "reference": {str(t): v for t, v in ref.items()},
        "load_average": load,
        "published": {"seconds": peer_s, "cpu_seconds": peer_cpu, "error": peer_err, "at_t": peer_t,
                      "at": {str(t): v for t, v in peer.items()},
                      "bvp_iterations": iterations, "largest_mesh": largest},
        "eyeshell": {"tol": tol, "error": es_err, "at_t": es_t, "process_seconds": wall,
                     "process_cpu_seconds": es_cpu, "wall_seconds": inside,
                     "process_critical_cpu_seconds": critical, "solve_critical_cpu_seconds": threads, "nodes": accuracy.get("nodes"),
                     "rtol": accuracy.get("rtol"), "rounds": len(accuracy.get("rounds", []))},
        "speedup_process": peer_s / wall,
        "speedup_wall_seconds": peer_s / inside,
        "speedup_cpu": peer_cpu / es_cpu,
        "speedup_cpu_critical_process": peer_cpu / critical,
        "speedup_cpu_critical_solve": peer_cpu / threads,
        "accuracy_ratio": peer_err / es_err if es_err > 0 else float("inf"),
    }
    if a.json:
        print(json.dumps(report))
        return
    e = report["eyeshell"]
    print(f"reference: eyeshell IDA N = 3201, rtol 1e-10, atol 1e-12; at t = 1 axial length "
          f"{ref[1.0][0]:.9f}, equatorial radius {ref[1.0][1]:.9f} mm")
    print(f"published method (solve_bvp tol 1e-6 + 200 Euler steps, 501 points): error "
          f"{peer_err:.2e} mm (largest at t = {peer_t:g}); {peer_s:.2f} s ({peer_cpu:.2f} s CPU), "
          f"{iterations} "
          f"collocation iterations, largest mesh {largest}")
    print(f"eyeshell grow solver.tol = {tol:.1e} (chose N = {e['nodes']}, rtol "
          f"{e['rtol'] or float('nan'):.2g}, {e['rounds']} round(s)): error {es_err:.2e} mm "
          f"(largest at t = {es_t:g}); process {wall:.4f} s ({es_cpu:.4f} s CPU), summary "
          f"wall_seconds {inside:.4f} s (each the least of {a.repeat}); on two idle cores "
          f"(CPU less each round's cheaper thread) the process {critical:.4f} s, the solve "
          f"(each round's dearer thread) {threads:.4f} s")
    print(f"CPU against critical CPU: {report['speedup_cpu_critical_process']:.0f}x (process), "
          f"{report['speedup_cpu_critical_solve']:.0f}x (solve)")
    print(f"speed-up: {report['speedup_process']:.0f}x (process), "
          f"{report['speedup_wall_seconds']:.0f}x (wall_seconds), {report['speedup_cpu']:.0f}x "
          f"(CPU, process against process); eyeshell "
          f"{report['accuracy_ratio']:.0f}x more accurate; load average {load[0]:.1f} "
          f"{load[1]:.1f} {load[2]:.1f}")


if __name__ == "__main__":
    main()
