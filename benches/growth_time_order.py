#!/usr/bin/env python3
"""How far the time estimate of `solver.tol` in growth can be trusted (BENCHMARKS.md,
"Growth to a tolerance", the time estimator): on one mesh M, the true time error e(rtol)
of the axial length and the equatorial radius (the largest over the output times 0, 0.1,
0.2, 0.4, 1) against the same mesh at rtol 1e-10, beside three estimates of it from runs
on M at other rtols:

- fixed: |u(10·rtol) − u(rtol)| / (10^q − 1), q = 0.75 (growth/tolerance.rs TIME_ORDER,
  what summary.json's error_estimate reports);
- measured: the same with q = log10(|u(100·rtol) − u(10·rtol)| / |u(10·rtol) − u(rtol)|),
  the order each run would measure with one more companion (clamped to [0.75, 1.5]);
- ratio 3: |u(3·rtol) − u(rtol)| / (3^q − 1), q = 0.75, a companion nearer to rtol.

Printed per scene and rtol: e, the local order q_loc = log10(1 + d/e) that would make the
fixed estimate exact (d = |u(10·rtol) − u(rtol)|), and each estimate over e (Honest asks
[1/3, 30] of the total error; these are the time parts alone).

    cargo build --release && python3 benches/growth_time_order.py [--scenes const,thick,fibre]
        [--nodes 44] [--out DIR] [--bin EYESHELL]

Runs are kept in DIR and read back (delete DIR to rerun them).
"""

import argparse
import csv
import math
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = {
    "const": ("scenes/const.toml", []),
    "thick": ("scenes/thick.toml", []),
    "fibre": ("scenes/thick.toml", ["fibres.D=200"]),
}
RTOLS = [1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 1e-8]
TIME_ORDER = 0.75


def run(binary, scene, nodes, rtol, out):
    d = os.path.join(out, f"{scene}-n{nodes}-r{rtol:g}")
    if not os.path.exists(os.path.join(d, "summary.json")):
        path, base = SCENES[scene]
        cmd = [binary, "grow", os.path.join(ROOT, path), "--out", d, "--quiet",
               "--set", "output.history_points=0", "--set", f"solver.nodes={nodes}",
               "--set", f"solver.rtol={rtol}", "--set", f"solver.atol={rtol * 1e-2}"]
        for s in base:
            cmd += ["--set", s]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(d, "series.csv")) as f:
        return [(float(r["axial_length"]), float(r["equatorial_radius"])) for r in csv.DictReader(f)]


def dist(a, b):
    return max(max(abs(x[0] - y[0]), abs(x[1] - y[1])) for x, y in zip(a, b))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default="const,thick,fibre")
    ap.add_argument("--nodes", type=int, default=44, help="solver.nodes of M (44: the mesh "
                    "solver.tol = 1.8e-4 chooses on the const scene)")
    ap.add_argument("--out", default="out/growth_time_order")
    ap.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "eyeshell"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    print("| scene | rtol | true time error | q_loc | fixed / true | measured q | measured / true | ratio 3 / true |")
    print("|---|---|---|---|---|---|---|---|")
    for scene in a.scenes.split(","):
        tight = run(a.bin, scene, a.nodes, 1e-10, a.out)
        u = {r: run(a.bin, scene, a.nodes, r, a.out) for r in RTOLS}

        def at(x):
            return next((r for r in RTOLS if abs(r - x) / r < 1e-6), None)

        for r in RTOLS:
            r10, r100, r3 = at(10 * r), at(100 * r), at(3 * r) or at(10 * r / 3)
            if r10 is None:
                continue
            e = dist(u[r], tight)
            d1 = dist(u[r], u[r10])
            fixed = d1 / (10 ** TIME_ORDER - 1)
            cells = [f"{e:.2e}", f"{math.log10(1 + d1 / e):.2f}", f"{fixed / e:.2f}"]
            if r100 is not None:
                q = math.log10(dist(u[r10], u[r100]) / d1)
                qc = min(max(q, 0.75), 1.5)
                cells += [f"{q:.2f}", f"{d1 / (10 ** qc - 1) / e:.2f}"]
            else:
                cells += ["", ""]
            if r3 is not None:
                rho = r3 / r
                cells.append(f"{dist(u[r], u[r3]) / (rho ** TIME_ORDER - 1) / e:.2f}")
            else:
                cells.append("")
            print(f"| {scene} | {r:g} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
