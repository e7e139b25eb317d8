#!/usr/bin/env python3
"""Forward sensitivities against finite differences at equal accuracy (issue 19;
BENCHMARKS.md, "Sensitivities against finite differences").

The alternative to `--sensitivities` is k + 1 runs (forward differences) or 2k runs
(central differences) with each parameter perturbed. Their accuracy depends on the runs'
tolerance and the step, so this measures both ways' error in dL/dp (L the axial length,
every output time, every parameter) against a reference, with their on-CPU cost:

- the reference: a sensitivity run at rtol 1e-11, atol 1e-13 (with
  `--reference-error-control`: with error control on the sensitivities, at
  `--reference-rtol`, which converges where the uncontrolled sensitivities stall near 1e-4);
- sensitivity runs at rtol 1e-6, 1e-8, 1e-10 (with `--error-control-rows`: also with
  error control, at rtol 1e-6 and 1e-8);
- forward and central differences of runs at rtol 1e-6, 1e-8, 1e-10 with relative steps
  1e-2, 1e-3, 1e-4, 1e-5.

Error of one way: the largest over parameters of max_t |dL/dp − ref| / max_t |ref|.
Cost: on-CPU seconds (user + system of the child processes, getrusage), the smallest of
--reps repetitions for the sensitivity runs; the difference quotients' cost is the sum
of their runs. Printed: two Markdown tables.

    cargo build --release
    python3 benches/sensitivity_vs_differences.py
    python3 benches/sensitivity_vs_differences.py --reference-error-control \
        --reference-rtol 1e-10 --error-control-rows
"""

import argparse
import csv
import os
import resource
import subprocess
import tempfile

KEYS = {
    "growth.eta0": 70.0, "growth.Gamma": 8.0, "growth.delta": 4.0, "material.C": 100.0,
    "material.bending": 18.0, "pressure.dP": 2.0, "stimulus.blue.z_B": None,
}


def grow(binary, scene, sets, out, keys=None, error_control=False):
    """One run: (on-CPU seconds, {t: L}, {(key, t): dL/dp})."""
    args = [binary, "grow", scene, "--set", "output.history_points=0", "--out", out, "-q"]
    for s in sets:
        args += ["--set", s]
    if keys:
        args += ["--sensitivities", ",".join(keys)]
    if error_control:
        args += ["--sensitivity-error-control"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(args, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with open(os.path.join(out, "series.csv")) as f:
        length = {float(r["t"]): float(r["axial_length"]) for r in csv.DictReader(f)}
    sens = {}
    if keys:
        with open(os.path.join(out, "sensitivities.csv")) as f:
            for r in csv.DictReader(f):
                sens[(r["parameter"], float(r["t"]))] = float(r["d_axial_length"])
    return cpu, length, sens


def error(est, ref, keys, times):
    worst = 0.0
    for k in keys:
        scale = max(abs(ref[(k, t)]) for t in times)
        worst = max(worst, max(abs(est[(k, t)] - ref[(k, t)]) for t in times) / scale)
    return worst


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--binary", default="target/release/eyeshell")
    ap.add_argument("--scene", default="scenes/const.toml")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--reference-rtol", type=float, default=1e-11)
    ap.add_argument("--reference-error-control", action="store_true")
    ap.add_argument("--error-control-rows", action="store_true")
    a = ap.parse_args()
    keys = list(KEYS)
    tol = lambda r: [f"solver.rtol={r}", f"solver.atol={r * 1e-2}"]
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "run")
        _, _, ref = grow(a.binary, a.scene, tol(a.reference_rtol), out, keys,
                         a.reference_error_control)
        times = sorted({t for (_, t) in ref if t > 0})
        # The parameters' values: scaled = (p/L) dL/dp is in the files; p is also in KEYS.
        values = dict(KEYS)
        with open(os.path.join(out, "sensitivities.csv")) as f:
            for r in csv.DictReader(f):
                if values[r["parameter"]] is None and float(r["d_axial_length"]) != 0:
                    _, length, _ = grow(a.binary, a.scene, tol(1e-11), out)
                    L = length[float(r["t"])]
                    values[r["parameter"]] = float(r["scaled_axial_length"]) * L / float(r["d_axial_length"])
        print("| way | rtol | step | runs | on-CPU | error |\n|---|---|---|---|---|---|")
        for rtol in (1e-6, 1e-8, 1e-10):
            best, sens = None, None
            for _ in range(a.reps):
                cpu, _, s = grow(a.binary, a.scene, tol(rtol), out, keys)
                best, sens = min(cpu, best or cpu), s
            print(f"| sensitivities (k = {len(keys)}) | {rtol:g} | – | 1 | {best:.3f} s | {error(sens, ref, keys, times):.1e} |")
        for rtol in (1e-6, 1e-8) if a.error_control_rows else ():
            cpu, _, s = grow(a.binary, a.scene, tol(rtol), out, keys, True)
            print(f"| sensitivities with error control (k = {len(keys)}) | {rtol:g} | – | 1 | {cpu:.3f} s | {error(s, ref, keys, times):.1e} |", flush=True)
        for rtol in (1e-6, 1e-8, 1e-10):
            cpu0, base, _ = grow(a.binary, a.scene, tol(rtol), out)
            for h in (1e-2, 1e-3, 1e-4, 1e-5):
                fwd, cen, cost_p, cost_m = {}, {}, 0.0, 0.0
                for k in keys:
                    dp = h * abs(values[k])
                    c1, plus, _ = grow(a.binary, a.scene, tol(rtol) + [f"{k}={values[k] + dp!r}"], out)
                    c2, minus, _ = grow(a.binary, a.scene, tol(rtol) + [f"{k}={values[k] - dp!r}"], out)
                    cost_p, cost_m = cost_p + c1, cost_m + c2
                    for t in times:
                        fwd[(k, t)] = (plus[t] - base[t]) / dp
                        cen[(k, t)] = (plus[t] - minus[t]) / (2 * dp)
                n = len(keys)
                print(f"| forward differences | {rtol:g} | {h:g} | {n + 1} | {cpu0 + cost_p:.3f} s | {error(fwd, ref, keys, times):.1e} |")
                print(f"| central differences | {rtol:g} | {h:g} | {2 * n} | {cost_p + cost_m:.3f} s | {error(cen, ref, keys, times):.1e} |")


if __name__ == "__main__":
    main()
