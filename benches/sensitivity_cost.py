#!/usr/bin/env python3
"""The cost of forward sensitivities against a plain growth run (issue 19; BENCHMARKS.md,
"Forward sensitivities"), measured on the CLI as a user runs it.

Each run is `eyeshell grow SCENE --set output.history_points=0 [--sensitivities KEYS]`;
its cost is the process's on-CPU time (user + system, from getrusage: the machine is
shared, and other processes' load stretches the wall clock but not this). The runs are
interleaved (plain, then each key list, repeated) and the smallest of the repetitions is
kept. Printed: a Markdown table with k, the keys, the on-CPU seconds, the ratio to the
plain run, k + 1, IDAS's steps and sensitivity iterations, and the F_y assemblies and
seconds that summary.json's `sensitivities` records (wall-clock seconds inside the run,
the smallest over the repetitions: a loaded machine stretches them).

    cargo build --release
    python3 benches/sensitivity_cost.py --reps 7 growth.eta0 \\
        growth.eta0,growth.Gamma growth.eta0,growth.Gamma,growth.delta

Any key list `eyeshell grow --sensitivities` accepts works (k = 4, 7 once the elastic
parameters are supported).
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile


def run(binary, scene, keys, out):
    """One run: (on-CPU seconds, summary.json)."""
    args = [binary, "grow", scene, "--set", "output.history_points=0", "--out", out, "-q"]
    if keys:
        args += ["--sensitivities", keys]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(args, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with open(os.path.join(out, "summary.json")) as f:
        return cpu, json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("keys", nargs="+", help="comma-separated scene keys, one list per run")
    ap.add_argument("--scene", default="scenes/const.toml")
    ap.add_argument("--binary", default="target/release/eyeshell")
    ap.add_argument("--reps", type=int, default=7)
    a = ap.parse_args()
    lists = [""] + a.keys
    best, fy = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "run")
        for _ in range(a.reps):
            for keys in lists:
                cpu, summary = run(a.binary, a.scene, keys, out)
                if keys not in best or cpu < best[keys][0]:
                    best[keys] = (cpu, summary)
                sens = summary.get("sensitivities")
                if sens and "jacobian_seconds" in sens:  # (older binaries lack it)
                    fy[keys] = min(fy.get(keys, float("inf")), sens["jacobian_seconds"])
    plain = best[""][0]
    print("| k | parameters | on-CPU | ratio to plain | k + 1 | steps "
          "| sensitivity iterations | F_y assemblies | F_y wall seconds |")
    print("|---|---|---|---|---|---|---|---|---|")
    for keys in lists:
        cpu, s = best[keys]
        k = len(keys.split(",")) if keys else 0
        sens = s.get("sensitivities") or {}
        print(f"| {k} | {keys or '(plain run)'} | {cpu:.3f} s | {cpu / plain:.2f} | {k + 1} "
              f"| {s['steps']} | {sens.get('nonlinear_iterations', '–')} "
              f"| {sens.get('jacobian_assemblies', '–')} "
              f"| {fy.get(keys, float('nan')):.3f} s |" if sens else
              f"| {k} | (plain run) | {cpu:.3f} s | 1 | 1 | {s['steps']} | – | – | – |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
