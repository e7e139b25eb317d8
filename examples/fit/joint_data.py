"""The data of the user guide's joint fit (docs/guide/sensitivities.md, "Several arms"):
scenes/eyewear/none.toml and single-vision.toml on 61 nodes grown at (eta0, Gamma) =
(75, 7.5), their axial lengths and refractions at t = 0.1, 0.2, ..., 1 plus N(0, 0.03^2) mm
and N(0, 0.15^2) D noise from Python's random.Random(seed) (seed 1 and 2), rounded to
1e-4, written as joint_none.csv and joint_single-vision.csv beside this file.

    python3 examples/fit/joint_data.py   # needs `eyeshell` on PATH
"""
import csv
import pathlib
import random
import subprocess
import tempfile

HERE = pathlib.Path(__file__).resolve().parent
SCENES = HERE.parents[1] / "scenes" / "eyewear"
TIMES = [i / 10 for i in range(1, 11)]

for seed, arm in [(1, "none"), (2, "single-vision")]:
    with tempfile.TemporaryDirectory() as out:
        subprocess.run(
            ["eyeshell", "grow", str(SCENES / f"{arm}.toml"), "--set", "solver.nodes=61",
             "--set", "growth.eta0=75", "--set", "growth.Gamma=7.5",
             "--set", "output.history_points=0",
             "--set", "output.times=[" + ",".join(map(str, TIMES)) + "]",
             "--out", f"{out}/run", "-q"],
            check=True,
        )
        with open(f"{out}/run/series.csv") as f:
            rows = [r for r in csv.DictReader(f) if float(r["t"]) > 0]
    noise = random.Random(seed)
    with open(HERE / f"joint_{arm}.csv", "w") as f:
        f.write("t,axial_length,sigma_axial_length,refraction_D,sigma_refraction_D\n")
        for r in rows:
            length = float(r["axial_length"]) + noise.gauss(0, 0.03)
            power = float(r["refraction_D"]) + noise.gauss(0, 0.15)
            f.write(f"{float(r['t']):g},{length:.4f},0.03,{power:.4f},0.15\n")
