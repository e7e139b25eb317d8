"""eyeshell.grow(..., sensitivities=[...]) against `eyeshell grow --sensitivities`, bit for
bit, and eyeshell.fit: recovery on synthetic data, the command line's fit, refusals."""

import json

import numpy as np
import pytest

import eyeshell
from conftest import ROOT, SCENES, read_csv

DATA = ROOT / "examples" / "fit" / "const_synthetic.csv"
KEYS = ["growth.eta0", "growth.Gamma", "growth.delta"]


def test_sensitivities_equal_the_command_lines_file_bit_for_bit(cli, tmp_path):
    run = tmp_path / "run"
    cli("grow", SCENES / "const.toml", "--set", "solver.nodes=101", "--sensitivities",
        ",".join(KEYS), "--out", run, "--quiet")
    g = eyeshell.grow(SCENES / "const.toml", frames=False, solver__nodes=101, sensitivities=KEYS)
    written = read_csv(run / "sensitivities.csv")
    assert list(written) == list(g.sensitivities)
    for column, values in written.items():
        assert list(g.sensitivities[column]) == values, column
    assert len(values) == 3 * len(g.history["t"])  # every recorded time, every key
    summary = json.loads((run / "summary.json").read_text())
    assert g.summary["sensitivities"]["parameters"] == summary["sensitivities"]["parameters"] == KEYS


def test_without_sensitivities_the_table_is_empty_and_bad_keys_are_refused():
    g = eyeshell.grow(SCENES / "const.toml", frames=False, solver__nodes=101)
    assert len(g.sensitivities["t"]) == 0 and list(g.sensitivities["parameter"]) == []
    with pytest.raises(eyeshell.InputError, match="only affects the classification"):
        eyeshell.grow(SCENES / "const.toml", sensitivities=["stimulus.red.offset"])
    with pytest.raises(eyeshell.InputError, match='need solver.integrator = "ida"'):
        eyeshell.grow(SCENES / "const.toml", sensitivities=["growth.eta0"],
                      solver__integrator="cvode")
    # Bad input, not a solver failure: the scene has no fibres.
    with pytest.raises(eyeshell.InputError, match="fibres.D = 0: the scene has no fibres"):
        eyeshell.grow(SCENES / "const.toml", sensitivities=["fibres.D"])


def test_fit_recovers_eta0_gamma_delta_from_synthetic_data():
    truth = eyeshell.Scene.from_file(SCENES / "const.toml", solver__nodes=101)
    times = np.arange(1, 11) / 10
    g = eyeshell.grow(truth, frames=False, output__history_points=10)
    exact = np.asarray(g.history["axial_length"])[1:]
    assert np.allclose(np.asarray(g.history["t"])[1:], times)
    rng = np.random.default_rng(5)
    data = {"t": times, "axial_length": exact + 0.05 * rng.standard_normal(10),
            "sigma": np.full(10, 0.05)}
    r = eyeshell.fit(truth, data, fit=KEYS, frames=False,
                     growth__eta0=60, growth__Gamma=9, growth__delta=3.5)
    assert r.converged and r.iterations <= 12, r.report["convergence_reason"]
    for key, value in zip(KEYS, [70.0, 8.0, 4.0]):
        assert abs(r.estimates[key] - value) < 2 * r.standard_errors[key], (key, r)
        assert r.initial[key] != value
        assert r.scene[key] == r.estimates[key]
    assert r.correlation.shape == (3, 3) and np.allclose(np.diag(r.correlation), 1)
    assert np.allclose(r.residuals["residual"], r.residuals["model"] - r.residuals["axial_length"])
    c = r.curve(21)
    # Another run (other output times, so other steps): the same to the run's tolerance.
    assert len(c["t"]) == 21 and abs(c["axial_length"][-1] - r.residuals["model"][-1]) < 1e-4
    assert "growth.eta0 = " in repr(r)


def test_fit_of_a_file_is_the_command_lines(cli, tmp_path):
    out = tmp_path / "fit"
    cli("fit", SCENES / "const.toml", "--set", "solver.nodes=101", "--set", "growth.Gamma=9",
        "--data", DATA, "--fit", "growth.Gamma,growth.delta", "--out", out, "--quiet")
    written = json.loads((out / "fit.json").read_text())
    r = eyeshell.fit(SCENES / "const.toml", DATA, fit="growth.Gamma,growth.delta",
                     solver__nodes=101, growth__Gamma=9)
    for a, b in zip(written["parameters"], r.report["parameters"]):
        assert a["estimate"] == b["estimate"] and a["standard_error"] == b["standard_error"]
    assert written["correlation"] == r.report["correlation"]
    assert written["data"]["fnv1a64"] == r.report["data"]["fnv1a64"]
    assert r.scene.to_toml() == eyeshell.Scene.from_file(out / "scene.toml").to_toml()


def test_fit_refusals_are_input_errors():
    with pytest.raises(eyeshell.InputError, match="cannot identify growth.Gamma"):
        eyeshell.fit(SCENES / "const.toml", DATA, fit=["growth.eta0", "growth.Gamma"],
                     solver__nodes=101, growth__Gamma=80, growth__delta=1)
    with pytest.raises(eyeshell.InputError, match="line 2: column 2 \\(axial_length\\) = NaN"):
        eyeshell.fit(SCENES / "const.toml", {"t": [0.5, 1], "axial_length": [float("nan"), 23]},
                     fit=["growth.Gamma"])
    with pytest.raises(eyeshell.InputError, match="is listed twice"):
        eyeshell.fit(SCENES / "const.toml", DATA, fit=["growth.Gamma", "growth.Gamma"])
    with pytest.raises(eyeshell.InputError, match="the columns t \\(or age, not both\\) and axial_length or refraction_D are required"):
        eyeshell.fit(SCENES / "const.toml", {"t": [0.5]}, fit=["growth.Gamma"])
    for bad in [0, 1001, True, 2.0]:
        with pytest.raises(eyeshell.InputError, match=f"max_iterations = {bad!r}: must be a whole number from 1 to 1,000"):
            eyeshell.fit(SCENES / "const.toml", DATA, fit=["growth.Gamma"], max_iterations=bad)
    r = eyeshell.fit(SCENES / "const.toml", DATA, fit=["growth.Gamma"], solver__nodes=101,
                     growth__Gamma=9, max_iterations=np.int64(1))
    assert r.iterations == 1 and not r.converged


@pytest.fixture(scope="module")
def fitted():
    # const.toml writes snapshots at t = 0.1, 0.2, 0.4: a curve must not take them in.
    return eyeshell.fit(SCENES / "const.toml", DATA, fit=["growth.Gamma"], solver__nodes=101)


@pytest.mark.parametrize("n", [2, 3, 5, 7, 21, np.int64(4)])
def test_the_curve_has_n_evenly_spaced_points_with_both_ends(fitted, n):
    c = fitted.curve(n)
    t_end = fitted.scene["growth.t_end"]
    # t_end·k/(n − 1), as the growth run computes its history times, bit for bit.
    assert np.array_equal(c["t"], t_end * np.arange(int(n)) / (int(n) - 1))
    assert len(c["axial_length"]) == n and np.all(np.isfinite(c["axial_length"]))
    assert np.all(np.diff(c["axial_length"]) > 0)
    # The fit's own scene is left as it was.
    assert fitted.scene["output.times"] == [0.1, 0.2, 0.4, 1.0]
    assert fitted.scene["output.history_points"] == 100


def test_the_curve_is_the_command_lines_fitted_curve(fitted):
    # The command line plots fit::curve at 201 points; the default here is the same.
    c = fitted.curve()
    assert len(c["t"]) == 201 and c["t"][100] == 0.5


@pytest.mark.parametrize("n, needle", [
    (0, "points = 0: must be a whole number from 2 to 1,000,001"),
    (1, "points = 1: must be a whole number from 2 to 1,000,001"),
    (-5, "points = -5: must be a whole number from 2"),
    (10**7, "points = 10000000: must be a whole number from 2 to 1,000,001"),
    (True, "points = True: must be a whole number"),
    (3.0, "points = 3.0: must be a whole number"),
    ("3", "points = '3': must be a whole number"),
])
def test_a_curve_of_fewer_than_two_points_or_not_a_count_is_refused(fitted, n, needle):
    with pytest.raises(eyeshell.InputError) as e:
        fitted.curve(n)
    assert needle in str(e.value)


# Ages 2 to 12 years, η0 per year (the paper's 70 over those 10 years), and const.toml's
# output times as the ages they stand for (its 0.1, 0.2, 0.4, 1 of the window).
YEARS = dict(time__unit="years", time__start=2.0, time__end=12.0, growth__eta0=7.0,
             output__times=[3.0, 4.0, 6.0, 12.0], solver__nodes=21, output__history_points=4)


def test_a_scene_in_years_carries_ages_as_the_command_line_writes_them(cli, tmp_path):
    """series, history, sensitivities, peripheral and the snapshots end in an age column
    (age = 2 + t here), bit for bit the command line's files; without time.unit there
    is none."""
    scene = eyeshell.Scene.from_file(SCENES / "const.toml", **YEARS)
    toml = tmp_path / "years.toml"
    toml.write_text(scene.to_toml())
    run = tmp_path / "run"
    cli("grow", toml, "--sensitivities", "growth.eta0", "--out", run, "--quiet")
    g = eyeshell.grow(scene, frames=False, sensitivities=["growth.eta0"])
    for name, table in [("series.csv", g.series), ("history.csv", g.history),
                        ("sensitivities.csv", g.sensitivities), ("peripheral.csv", g.peripheral)]:
        written = read_csv(run / name)
        assert list(written)[-1] == "age" and list(written) == list(table), name
        assert list(table["age"]) == written["age"], name
        assert np.allclose(table["age"], 2 + np.asarray(table["t"]), rtol=0, atol=1e-12)
    # Each snapshot ends in its age on every node, as its file does.
    files = sorted((run / "snapshots").iterdir())
    assert len(files) == len(g.snapshots) >= 3
    for path, (t, fields) in zip(files, sorted(g.snapshots.items())):
        written = read_csv(path)
        assert list(written)[-1] == "age" and list(written) == list(fields), path.name
        assert list(fields["age"]) == written["age"] == [2 + t] * len(fields["r"]), path.name
    plain = eyeshell.grow(SCENES / "const.toml", frames=False, solver__nodes=21)
    assert "age" not in plain.series and "age" not in plain.sensitivities
    assert "age" not in plain.peripheral
    assert all("age" not in fields for fields in plain.snapshots.values())


def test_fit_takes_data_by_age_and_reports_by_age():
    """The series' own lengths at its ages, η0 started 10 % off: recovered, and the
    residuals and the curve carry the ages; t and age together are refused."""
    scene = eyeshell.Scene.from_file(SCENES / "const.toml", **YEARS)
    g = eyeshell.grow(scene, frames=False)
    data = {"age": g.series["age"][1:], "axial_length": g.series["axial_length"][1:],
            "sigma": [0.05] * (len(g.series["age"]) - 1)}
    r = eyeshell.fit(scene, data, fit=["growth.eta0"], frames=False, growth__eta0=6.3)
    assert abs(r.estimates["growth.eta0"] - 7) < 0.005
    assert list(r.residuals["age"]) == list(data["age"])
    assert "residuals        age (years)" in r.text
    c = r.curve(3)
    assert list(c["age"]) == [2.0, 7.0, 12.0]
    with pytest.raises(eyeshell.InputError, match="t \\(or age, not both\\)"):
        eyeshell.fit(scene, {**data, "t": [0.1] * len(data["age"])}, fit=["growth.eta0"])
    with pytest.raises(eyeshell.InputError, match="lies outside the scene's ages"):
        eyeshell.fit(scene, {**data, "age": [1.0] * len(data["age"])}, fit=["growth.eta0"])


@pytest.mark.parametrize("frame", [False, True])
@pytest.mark.parametrize("name, needle", [
    ("sd", "column 'sd' (the standard deviation is the column 'sigma')"),
    ("Sigma", "column 'Sigma' (did you mean 'sigma'?)"),
    ("weight", "column 'weight' is not one the fit reads"),
])
def test_fit_data_with_a_column_it_does_not_read_is_refused(frame, name, needle):
    # The command line refuses the header, and so does Python: a dropped sigma column would
    # fit unweighted without a word.
    data = {"t": [0.5, 0.75, 1.0], "axial_length": [23.0, 23.5, 24.0], name: [0.05] * 3}
    if frame:
        pandas = pytest.importorskip("pandas")
        data = pandas.DataFrame(data)
    with pytest.raises(eyeshell.InputError, match=needle.replace("(", r"\(").replace(")", r"\)").replace("?", r"\?")):
        eyeshell.fit(SCENES / "const.toml", data, fit=["growth.Gamma"], solver__nodes=101)


def test_an_out_of_range_keyword_is_blamed_on_the_keyword():
    # Not on the scene file, nor on "defaults:", which did not set it.
    for scene in (SCENES / "const.toml", None):
        with pytest.raises(eyeshell.InputError) as e:
            eyeshell.grow(scene, growth__eta0=-1)
        assert str(e.value).startswith("set growth.eta0=-1: growth.eta0"), str(e.value)
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.fit(SCENES / "const.toml", DATA, fit=["growth.Gamma"], solver__nodes=3)
    assert str(e.value).startswith("set solver.nodes=3: solver.nodes"), str(e.value)


JOINT = ROOT / "examples" / "fit"
EYEWEAR = SCENES / "eyewear"


def _joint_arms(data_of=lambda path: path):
    return {
        "none": (EYEWEAR / "none.toml", data_of(JOINT / "joint_none.csv")),
        "single-vision": (EYEWEAR / "single-vision.toml", data_of(JOINT / "joint_single-vision.csv")),
    }


def test_a_joint_fit_of_two_arms_is_the_command_lines(cli, tmp_path):
    out = tmp_path / "joint"
    cli("fit", "--set", "solver.nodes=61", "--set", "output.history_points=0",
        "--arm", f"none={EYEWEAR / 'none.toml'}:{JOINT / 'joint_none.csv'}",
        "--arm", f"single-vision={EYEWEAR / 'single-vision.toml'}:{JOINT / 'joint_single-vision.csv'}",
        "--fit", "growth.Gamma", "--per-arm", "growth.eta0", "--out", out, "--quiet")
    written = json.loads((out / "fit.json").read_text())
    r = eyeshell.fit(fit=["growth.Gamma"], per_arm=["growth.eta0"], arms=_joint_arms(),
                     frames=False, solver__nodes=61, output__history_points=0)
    assert r.keys == ["growth.Gamma", "growth.eta0[none]", "growth.eta0[single-vision]"]
    for a, b in zip(written["parameters"], r.report["parameters"]):
        assert a["estimate"] == b["estimate"] and a["standard_error"] == b["standard_error"]
    # Both arms were grown at η0 = 75, Γ = 7.5.
    for key, truth in [("growth.Gamma", 7.5), ("growth.eta0[none]", 75), ("growth.eta0[single-vision]", 75)]:
        assert abs(r.estimates[key] - truth) < 2 * r.standard_errors[key], key
    assert set(r.scenes) == {"none", "single-vision"}
    assert r.scenes["none"]["growth.eta0"] == r.estimates["growth.eta0[none]"]
    assert r.scenes["single-vision"]["growth.Gamma"] == r.estimates["growth.Gamma"]
    res = r.residuals
    assert list(res["arm"][:2]) == ["none", "none"] and res["arm"][-1] == "single-vision"
    assert len(res["t"]) == 40
    # Rows alternate: an axial length (refraction NaN), then a refraction (length NaN).
    assert np.isnan(res["refraction_D"][0]) and np.isnan(res["axial_length"][1])
    assert res["refraction_D"][1] == 5.47


def test_a_joint_fit_takes_columns_with_nan_for_a_quantity_not_measured():
    import csv

    def columns(path):
        with open(path) as f:
            rows = list(csv.DictReader(f))
        cols = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
        # The first visit measured the axial length only.
        cols["refraction_D"][0] = cols["sigma_refraction_D"][0] = np.nan
        return cols

    r = eyeshell.fit(fit="growth.eta0,growth.Gamma", arms=_joint_arms(columns), frames=False,
                     solver__nodes=61, output__history_points=0)
    assert r.converged and len(r.residuals["t"]) == 38
    for key, truth in [("growth.Gamma", 7.5), ("growth.eta0", 75)]:
        assert abs(r.estimates[key] - truth) < 2 * r.standard_errors[key], key


def test_joint_fit_refusals_are_input_errors():
    with pytest.raises(eyeshell.InputError, match="the scene computes no refraction"):
        eyeshell.fit(SCENES / "const.toml", JOINT / "joint_none.csv", fit=["growth.eta0"])
    with pytest.raises(eyeshell.InputError, match="not both"):
        eyeshell.fit(SCENES / "const.toml", DATA, fit=["growth.eta0"], arms=_joint_arms())
    with pytest.raises(eyeshell.InputError, match="growth.eta0 is fitted per arm: a key of each arm's own needs two arms"):
        eyeshell.fit(SCENES / "const.toml", DATA, fit=["growth.Gamma"], per_arm=["growth.eta0"])
    with pytest.raises(eyeshell.InputError, match="optics.surfaces\\[0\\].radius is not used by the run"):
        eyeshell.fit(SCENES / "const.toml", DATA, fit=["optics.surfaces[0].radius"])
    with pytest.raises(TypeError, match="must be a \\(scene, data\\) pair"):
        eyeshell.fit(fit=["growth.eta0"], arms={"a": SCENES / "const.toml"})
