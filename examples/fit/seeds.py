"""The fit of BENCHMARKS.md's "Calibration" repeated over 20 noise draws: the const scene on
101 nodes at (eta0, Gamma, delta) = (70, 8, 4), its axial lengths at t = 0.1, ..., 1 plus
N(0, 0.05^2) noise from numpy's default_rng(seed), seed = 0..19, fitted from (60, 9, 3.5).
Per seed: iterations, growth runs, the stopping test, each estimate minus the truth in
standard errors, CPU and wall seconds, chi2 and the standard errors.

    python3 examples/fit/seeds.py
"""
import pathlib
import time

import numpy as np

import eyeshell

SC = pathlib.Path(__file__).resolve().parents[2] / "scenes" / "const.toml"
truth = eyeshell.Scene.from_file(SC, solver__nodes=101)
times = np.arange(1, 11) / 10
g = eyeshell.grow(truth, frames=False, output__history_points=10)
exact = np.asarray(g.history["axial_length"])[1:]
K=["growth.eta0","growth.Gamma","growth.delta"]
inside=0; its=[]; secs=[]
for seed in range(20):
    rng = np.random.default_rng(seed)
    data = {"t": times, "axial_length": exact + 0.05 * rng.standard_normal(10), "sigma": np.full(10, 0.05)}
    t0=time.process_time()
    try:
        r = eyeshell.fit(truth, data, fit=K, frames=False, growth__eta0=60, growth__Gamma=9, growth__delta=3.5)
    except Exception as e:
        print(seed, "ERR", e); continue
    cpu=time.process_time()-t0
    z=[(r.estimates[k]-v)/r.standard_errors[k] for k,v in zip(K,[70,8,4])]
    inside += all(abs(x)<2 for x in z); its.append(r.iterations); secs.append(cpu)
    print(seed, r.iterations, r.report["model_runs"], r.report["convergence"], ["%.2f"%x for x in z], "cpu %.2fs wall %.2fs"%(cpu, r.report["wall_seconds"]), "chi2 %.4f"%r.chi2, "se", ["%.3g"%r.standard_errors[k] for k in K])
print("all within 2 se:", inside, "/ 20; iterations median", np.median(its), "max", max(its), "; cpu s median %.2f max %.2f"%(np.median(secs), max(secs)))
