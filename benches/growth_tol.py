#!/usr/bin/env python3
"""Growth to a tolerance (BENCHMARKS.md, "Growth to a tolerance"): for each scene and each
solver.tol, the delivered error of the axial length and the equatorial radius (the largest
over the output times) against a reference, the estimate summary.json reports, the run's
seconds (its choice included), and the cheapest (N, rtol) of a hand-picked grid that meets
the same tol, with its seconds.

    cargo build --release && python3 benches/growth_tol.py [--scenes const,thick,fibre]
        [--tols 1e-3,1e-4,1e-5,1e-6,1e-7] [--out DIR]

The reference of each scene is IDA on N = 3201 nodes at rtol 1e-10 (atol 1e-12); for the
const scene CVODE on N = 1601 at rtol 1e-10 is run beside it and their distance printed.
Times are each run's summary `wall_seconds`, the least of --repeat runs.
"""

import argparse
import csv
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EYESHELL = os.path.join(ROOT, "target", "release", "eyeshell")
SCENES = {
    "const": ("scenes/const.toml", []),
    "thick": ("scenes/thick.toml", []),
    "fibre": ("scenes/thick.toml", ["fibres.D=200"]),
}
GRID_N = [26, 51, 101, 201, 401, 801, 1601]
GRID_RTOL = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]


def grow(scene, sets, out):
    path, base = SCENES[scene]
    cmd = [EYESHELL, "grow", os.path.join(ROOT, path), "--out", out,
           "--set", "output.history_points=0"]
    for s in base + sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "series.csv")) as f:
        rows = [(float(r["axial_length"]), float(r["equatorial_radius"]))
                for r in csv.DictReader(f)]
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    return rows, summary


def error(rows, ref):
    return max(max(abs(a[0] - b[0]), abs(a[1] - b[1])) for a, b in zip(rows, ref))


def timed(scene, sets, out, repeat):
    best = None
    for _ in range(repeat):
        rows, summary = grow(scene, sets, out)
        if best is None or summary["wall_seconds"] < best[1]["wall_seconds"]:
            best = (rows, summary)
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", default="const,thick,fibre")
    ap.add_argument("--tols", default="1e-3,1e-4,1e-5,1e-6,1e-7")
    ap.add_argument("--out", default="out/growth_tol")
    ap.add_argument("--repeat", type=int, default=1)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    tols = [float(t) for t in a.tols.split(",")]
    print("| scene | tol | nodes, rtol chosen | rounds | delivered error | estimate | estimate / error | seconds | cheapest grid (N, rtol) | its error | its seconds | seconds / grid's |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for scene in a.scenes.split(","):
        d = lambda name: os.path.join(a.out, f"{scene}-{name}")
        ref, _ = grow(scene, ["solver.nodes=3201", "solver.rtol=1e-10", "solver.atol=1e-12"], d("ref"))
        if scene == "const":
            cv, _ = grow(scene, ["solver.nodes=1601", "solver.rtol=1e-10", "solver.atol=1e-12",
                                 "solver.integrator=cvode"], d("ref-cvode"))
            print(f"<!-- {scene}: IDA N=3201 against CVODE N=1601, both rtol 1e-10: {error(cv, ref):.2e} mm -->", file=sys.stderr)
        grid = []
        for n in GRID_N:
            for r in GRID_RTOL:
                rows, s = timed(scene, [f"solver.nodes={n}", f"solver.rtol={r}", f"solver.atol={r * 1e-2}"],
                                d(f"n{n}-r{r}"), a.repeat)
                grid.append((n, r, error(rows, ref), s["wall_seconds"]))
        for tol in tols:
            try:
                rows, s = timed(scene, [f"solver.tol={tol}"], d(f"tol{tol}"), a.repeat)
            except subprocess.CalledProcessError:
                print(f"| {scene} | {tol:g} | failed | | | | | | | | | |")
                continue
            e = error(rows, ref)
            est = s["error_estimate"]
            estimate = max(est["axial_length"]["total"], est["equatorial_radius"]["total"])
            acc = s["accuracy"]
            ok = [g for g in grid if g[2] <= tol]
            cheapest = min(ok, key=lambda g: g[3]) if ok else None
            ch = (f"{cheapest[0]}, {cheapest[1]:g} | {cheapest[2]:.2e} | {cheapest[3]:.3f} | {s['wall_seconds'] / cheapest[3]:.1f}"
                  if cheapest else "none on the grid | | |")
            print(f"| {scene} | {tol:g} | {acc['nodes']}, {acc['rtol']:.1e} | {len(acc['rounds'])} | {e:.2e} | {estimate:.2e} | {estimate / e:.2f} | {s['wall_seconds']:.3f} | {ch} |", flush=True)


if __name__ == "__main__":
    main()
