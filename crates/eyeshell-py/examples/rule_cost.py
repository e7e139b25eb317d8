"""What a growth rule written in Python costs (BENCHMARKS.md, "A growth rule in Python";
docs/guide/python.md, "Rules in Python"): the const scene grown under the built-in paper's
rule and under the same rule in Python, ``lambda s: np.maximum(s.depth_mm, 0)``, at each
mesh; the wall time of both runs, the Python rule's calls and the time spent in them.

    python3 crates/eyeshell-py/examples/rule_cost.py [NODES ...]   (default: 101 501 2001)
"""

import pathlib
import sys
import time

import numpy as np

import eyeshell

CONST = pathlib.Path(__file__).resolve().parents[3] / "scenes" / "const.toml"


def papers(s):
    return np.maximum(s.depth_mm, 0)


def points(nodes):
    """The number of retinal points a rule sees at this mesh."""
    seen = []

    def count(s):
        seen.append(s.n)
        return papers(s)

    eyeshell.grow(CONST, frames=False, solver__nodes=nodes, growth__t_end=1e-3, output__times=[1e-3], stimulus=count)
    return seen[0]


def main(meshes):
    print("| nodes | points | built-in run | Python run | ratio | rule calls | in the rule | per call | per call and point | max \\|Δ axial length\\| |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for nodes in meshes:
        keys = {"solver__nodes": nodes, "solver__rtol": 1e-8, "frames": False}
        best = {}
        for name, rule in (("builtin", None), ("python", papers)):
            times = []
            for _ in range(3):
                start = time.perf_counter()
                g = eyeshell.grow(CONST, stimulus=rule, **keys)
                times.append(time.perf_counter() - start)
            best[name] = (min(times), g)
        (tb, b), (tp, p) = best["builtin"], best["python"]
        dl = np.max(np.abs(b.series["axial_length"] - p.series["axial_length"]))
        n, calls, spent = points(nodes), p.rule["calls"], p.rule["seconds"]
        print(
            f"| {nodes} | {n} | {tb:.3f} s | {tp:.3f} s | {tp / tb:.2f} | {calls} | {spent:.3f} s "
            f"| {spent / calls * 1e6:.0f} µs | {spent / calls / n * 1e9:.0f} ns | {dl:.1e} |"
        )


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [101, 501, 2001])
