#!/usr/bin/env python3
"""The trial study of docs/guide/trials.md: a growth rule fitted to the two arms of one
myopia-control trial and used, unchanged, to predict the arms of another.

    python3 examples/trials/study.py [--eyeshell PATH] [--rule local|integrated|both] --out DIR

1. Fit: Chamberlain et al. 2019 (chamberlain2019.csv), a single-vision contact lens against
   the MiSight dual-focus contact, 3-year changes in axial length and refraction. The arms
   are the child of scenes/myopia/ (−2 D at 8) wearing each lens, grown from 8 to 11; they
   share growth.eta0 (per year) and stimulus.myopic_gain (k_m, mm per D), fitted jointly to
   both arms' axial length and refraction (`eyeshell fit --arm`). The data are the scene's
   own baseline plus the trial's mean change, each with the standard error of its mean
   (the published SD over √n): the trial's baseline eye was not read (README.md), so the
   scene's stands for it and the fit sees the changes only.
2. Predict: Lam et al. 2020 (lam2020.csv), single-vision spectacles against the DIMS lenslet
   spectacle, at 6, 12, 18 and 24 months, from the completers' baseline ages (10.0 and 10.2
   years, lam2020_baseline.csv), the same child's eye, with the fitted values and nothing
   else changed. Each prediction is compared with the trial's mean change and its SE.

Every run is the eyeshell binary with argument lists (no shell). Each rule's runs go in
DIR/<rule>/ (the joint fit in DIR/<rule>/fit); the tables are printed as Markdown and
written to DIR/study.md."""
import argparse
import csv
import json
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
SCENES = os.path.join(REPO, "scenes", "myopia")
RULES = {"local": [], "integrated": ["stimulus.region=integrated"]}
# The Chamberlain arms: a single-vision −2 D contact lens and the MiSight-like one.
SV_CONTACT = 'optics.lenses=[{ kind = "contact", power = -2.0 }]'
FITTED = ["growth.eta0", "stimulus.myopic_gain"]


def run(eyeshell, args):
    r = subprocess.run([eyeshell] + args, capture_output=True, text=True)
    if r.returncode != 0:
        last = r.stderr.strip().splitlines()[-1] if r.stderr.strip() else "failed"
        sys.exit(f"study: {' '.join(args[:2])}: {last}")
    return r


def grow(eyeshell, scene, sets, out):
    args = ["grow", scene, "--out", out, "-q"]
    for s in sets:
        args += ["--set", s]
    run(eyeshell, args)
    with open(os.path.join(out, "series.csv")) as f:
        return [{k: float(v) for k, v in row.items() if k not in ("class",)} for row in csv.DictReader(f)]


def trial(name):
    with open(os.path.join(HERE, name)) as f:
        return list(csv.DictReader(f))


def se(row, quantity):
    """The standard error of an arm's mean change: the file's SE, or its SD over √n."""
    if row.get(f"{quantity}_se"):
        return float(row[f"{quantity}_se"])
    return float(row[f"{quantity}_sd"]) / math.sqrt(float(row["n"]))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--eyeshell", default=os.path.join(REPO, "target", "release", "eyeshell"))
    p.add_argument("--rule", choices=sorted(RULES) + ["both"], default="both")
    p.add_argument("--out", required=True)
    a = p.parse_args()
    if os.path.exists(a.out):
        sys.exit(f"study: --out {a.out!r} exists: give a new directory")
    os.makedirs(a.out)
    text = ""
    for name in sorted(RULES) if a.rule == "both" else [a.rule]:
        out = os.path.join(a.out, name)
        os.makedirs(out)
        text += study(a.eyeshell, name, out) + "\n"
    with open(os.path.join(a.out, "study.md"), "w") as f:
        f.write(text)
    print(text, end="")


def study(eyeshell, rule_name, out):
    """The fit and the prediction under one rule, in `out`; the tables as Markdown."""
    rule = RULES[rule_name]

    # 1. The fit's data: each Chamberlain arm's 3-year change on the scene's baseline.
    arms = {
        "single-vision": (os.path.join(SCENES, "dual-focus.toml"), [SV_CONTACT], "proclear_single_vision"),
        "dual-focus": (os.path.join(SCENES, "dual-focus.toml"), [], "misight_dual_focus"),
    }
    chamberlain = trial("chamberlain2019.csv")
    arm_args = []
    baselines = {}
    for name, (scene, sets, arm) in arms.items():
        base = grow(eyeshell, scene, rule + sets, os.path.join(out, f"baseline-{name}"))[0]
        baselines[name] = base
        row = next(r for r in chamberlain if r["arm"] == arm and r["years_from_baseline"] == "3")
        data = os.path.join(out, f"{name}.csv")
        with open(data, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["age", "axial_length", "sigma_axial_length", "refraction_D", "sigma_refraction_D"])
            w.writerow([11.0, base["axial_length"] + float(row["axial_length_mm"]), se(row, "axial_length"),
                        base["refraction_D"] + float(row["refraction_D"]), se(row, "refraction")])
        # The arm's scene as the fit reads it: the shipped scene with the rule and the lens.
        arm_scene = os.path.join(out, f"{name}.toml")
        text = run(eyeshell, ["check", scene] + sum((["--set", s] for s in rule + sets), [])).stdout
        with open(arm_scene, "w") as f:
            f.write(text)
        arm_args += ["--arm", f"{name}={arm_scene}:{data}"]
    fit_dir = os.path.join(out, "fit")
    args = ["fit"] + arm_args + sum((["--fit", k] for k in FITTED), []) + ["--out", fit_dir, "-q"]
    r = subprocess.run([eyeshell] + args, capture_output=True, text=True)
    if r.returncode == 2 and "cannot identify" in r.stderr:
        # A fit the data cannot make is a finding of the rule, not a failure of the study.
        return (f"Rule: defocus, {rule_name}. Fitted to Chamberlain 2019's two arms at 3 years: "
                f"no fit, and so no prediction. eyeshell says:\n\n> {r.stderr.strip()}\n")
    if r.returncode != 0:
        sys.exit(f"study: fit: {r.stderr.strip()}")
    with open(os.path.join(fit_dir, "fit.json")) as f:
        report = json.load(f)
    est = {p["key"]: (p["estimate"], p["standard_error"]) for p in report["parameters"]}

    # 2. The prediction: Lam's arms with the fitted values, from each arm's baseline age.
    lam = trial("lam2020.csv")
    ages = {r["arm"]: float(r["age_years"]) for r in trial("lam2020_baseline.csv")}
    fitted = [f"{k}={est[k][0]!r}" for k in FITTED]
    lines = [f"Rule: defocus, {rule_name}. Fitted to Chamberlain 2019's two arms at 3 years:", "",
             "| key | estimate | standard error |", "|---|---|---|"]
    lines += [f"| {k} | {est[k][0]:.4g} | {est[k][1]:.2g} |" for k in FITTED]
    lines += ["", f"χ² = {report['chi2']:.3g} on {report['degrees_of_freedom']} degrees of freedom "
              f"(the standard errors as the fit reports them, covariance_scaling = "
              f"{report['covariance_scaling']!r}). The fitted arms at 3 years (change from baseline):", "",
              "| arm | quantity | model | trial | z |", "|---|---|---|---|---|"]
    with open(os.path.join(fit_dir, "residuals.csv")) as f:
        for r in csv.DictReader(f):
            base = baselines[r["arm"]][r["measured"]]
            model, measured = float(r["model"]) - base, float(r["value"]) - base
            lines.append(f"| {r['arm']} | {r['measured']} | {model:+.3f} | {measured:+.2f} ± {float(r['sigma']):.3f} | "
                         f"{float(r['weighted_residual']):+.1f} |")
    lines += ["", "Predicted for Lam 2020 (change from baseline; trial mean ± SE; z = (model − trial)/SE):", "",
              "| arm | years | axial length: model | trial | z | refraction D: model | trial | z |",
              "|---|---|---|---|---|---|---|---|"]
    for arm, scene in (("single_vision", "single-vision.toml"), ("dims", "lenslets.toml")):
        start = ages[arm]
        visits = [float(r["years_from_baseline"]) for r in lam if r["arm"] == arm and r["kind"] == "change"]
        times = "[" + ", ".join(repr(start + v) for v in visits) + "]"
        series = grow(eyeshell, os.path.join(SCENES, scene),
                      rule + fitted + [f"time.start={start!r}", f"time.end={start + max(visits)!r}",
                                       f"output.times={times}"],
                      os.path.join(out, f"lam-{arm}"))
        base = series[0]
        for r in (r for r in lam if r["arm"] == arm and r["kind"] == "change"):
            at = next(s for s in series if abs(s["age"] - (start + float(r["years_from_baseline"]))) < 1e-9)
            dl, dr = at["axial_length"] - base["axial_length"], at["refraction_D"] - base["refraction_D"]
            tl, tr = float(r["axial_length_mm"]), float(r["refraction_D"])
            zl, zr = (dl - tl) / float(r["axial_length_se"]), (dr - tr) / float(r["refraction_se"])
            lines.append(f"| {arm} | {r['years_from_baseline']} | {dl:+.3f} | {tl:+.2f} ± {r['axial_length_se']} | "
                         f"{zl:+.1f} | {dr:+.2f} | {tr:+.2f} ± {r['refraction_se']} | {zr:+.1f} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
