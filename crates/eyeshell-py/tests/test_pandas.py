"""Python that fits pandas and NumPy: a sweep's results shaped as grow() shapes its own,
its values as numbers, one table for a whole sweep, grids in the caller's order, sweep
files usable from Python, keyword overrides set together, errors in Python's terms,
compare() on results, Growth.to_mat(), and a fit's notes and table."""

import math

import numpy as np
import pytest

import eyeshell
from conftest import ROOT, SCENES, optional

DATA = ROOT / "examples" / "fit" / "const_synthetic.csv"
GAMMA = {"growth.Gamma": [4, 8]}


def small(**overrides):
    return eyeshell.Scene.from_file(SCENES / "const.toml", solver__nodes=101, output__history_points=0,
                                    **overrides)


# Sweep results as grow() gives them, and their values as numbers.

def test_a_sweeps_series_are_the_data_frames_grow_gives():
    pandas = optional("pandas")
    runs = eyeshell.sweep(small(), grid=GAMMA, jobs=2)
    for r, gamma in zip(runs, GAMMA["growth.Gamma"]):
        alone = eyeshell.grow(small(), growth__Gamma=gamma)
        for name in ["series", "history", "sensitivities"]:
            assert isinstance(getattr(r.result, name), pandas.DataFrame), name
            pandas.testing.assert_frame_equal(getattr(r.result, name), getattr(alone, name))
    # frames=False: dicts of arrays, as grow(frames=False) gives them.
    for r in eyeshell.sweep(small(), grid=GAMMA, frames=False):
        assert isinstance(r.result.series, dict)
        assert isinstance(r.result.series["axial_length"], np.ndarray)
    for r in eyeshell.iter_sweep(small(), grid=GAMMA, frames=False):
        assert isinstance(r.result.series, dict)


def test_run_values_are_numbers_of_their_keys_type():
    scene = eyeshell.Scene(solver__nodes=101)
    runs = eyeshell.sweep(scene, grid={"fibres.D": [0, 200], "solver.nodes": [101, 121]},
                          runs=[{"name": "t", "solver.scheme": "trapezoid"}])
    assert [r.values for r in runs[:2]] == [
        {"solver.scheme": "trapezoid", "fibres.D": 0.0, "solver.nodes": 101},
        {"solver.scheme": "trapezoid", "fibres.D": 0.0, "solver.nodes": 121},
    ]
    assert all(type(r.values["fibres.D"]) is float for r in runs)
    assert all(type(r.values["solver.nodes"]) is int for r in runs)
    for r in runs:
        for key, value in r.values.items():
            assert r.result.scene[key] == value


# One table for a whole sweep.

def test_to_frame_has_a_row_per_run_and_output_time_with_the_swept_keys():
    pandas = optional("pandas")
    runs = eyeshell.sweep(small(), grid={"growth.delta": [4, 6], "growth.Gamma": [4, 8]}, jobs=2)
    df = runs.to_frame()
    assert isinstance(df, pandas.DataFrame)
    assert list(df.columns) == ["run", "status", "growth.delta", "growth.Gamma", "t", "axial_length",
                                "equatorial_radius", "retina_minus_blue", "retina_minus_red", "class",
                                "refraction_D", "drive", "defocus_D", "error"]
    times = len(runs[0].result.series)
    assert times == 5 and len(df) == 4 * times
    for r in runs:
        rows = df[df["run"] == r.name]
        assert list(rows["growth.delta"]) == [r.values["growth.delta"]] * times
        assert list(rows["growth.Gamma"]) == [r.values["growth.Gamma"]] * times
        for column in ["t", "axial_length", "equatorial_radius", "class", "refraction_D"]:
            assert list(rows[column]) == list(r.result.series[column]), column
    # The final rows are sweep.csv's final measures: a pivot is one line of pandas.
    final = df[df["t"] == 1.0].pivot(index="growth.delta", columns="growth.Gamma", values="axial_length")
    assert final.shape == (2, 2)
    assert final.loc[6.0, 8.0] == runs[3].result.series["axial_length"].iloc[-1]
    # The same without pandas, as lists.
    columns = runs.to_frame(frames=False)
    assert columns["axial_length"] == list(df["axial_length"])


def test_to_frame_of_a_sweep_in_years_has_the_age_after_t():
    # Ages 2 to 12 years: t = age − 2, η0 per year; an elastic run beside has none.
    years = small(time__unit="years", time__start=2.0, time__end=12.0, growth__eta0=7.0,
                  output__times=[7.0, 12.0])
    runs = eyeshell.sweep(years, grid=GAMMA, frames=False)
    elastic = eyeshell.RunResult("elastic", {}, "ok", eyeshell.solve(solver__nodes=41), None, 0.0, 2)
    columns = eyeshell.SweepResults([*runs, elastic]).to_frame(frames=False)
    names = list(columns)
    assert names[names.index("t") + 1] == "age", names
    assert len(columns["t"]) == 2 * 3 + 1
    for t, age in zip(columns["t"][:-1], columns["age"][:-1]):
        assert age == pytest.approx(2.0 + t, abs=1e-12), (t, age)
    assert math.isnan(columns["age"][-1])
    # A sweep without ages has no age column.
    assert "age" not in eyeshell.SweepResults(eyeshell.sweep(small(), grid=GAMMA)).to_frame(frames=False)


def test_to_frame_is_generic_over_the_runs_keys_and_keeps_failed_runs(monkeypatch):
    optional("pandas")
    monkeypatch.setenv("EYESHELL_TEST_ABORT_RUN", "thin")
    runs = eyeshell.sweep(eyeshell.Scene(solver__nodes=101),
                          runs=[{"name": "thin", "material.H0": 0.5}, {"name": "stiff", "fibres.D": 200},
                                {"name": "sphere"}])
    df = runs.to_frame()
    assert list(df["run"]) == ["thin", "stiff", "sphere"]  # elastic runs: one row each, t = 0
    assert list(df.columns[2:4]) == ["material.H0", "fibres.D"]
    assert df["material.H0"].iloc[0] == 0.5 and math.isnan(df["material.H0"].iloc[1])
    assert df["fibres.D"].iloc[1] == 200.0 and math.isnan(df["fibres.D"].iloc[2])
    assert list(df["status"]) == ["failed", "ok", "ok"]
    assert df["error"].iloc[0].startswith("the run's process ended abnormally") and df["error"].iloc[1] == ""
    assert math.isnan(df["axial_length"].iloc[0])
    assert list(df["t"].iloc[1:]) == [0.0, 0.0]
    # An elastic run's row is what `eyeshell sweep` measures of it (MODEL.md §6).
    eye = eyeshell.solve(eyeshell.Scene(solver__nodes=101), fibres__D=200).eye
    assert df["axial_length"].iloc[1] == eye["axial_length"] and 19 < eye["axial_length"] < 21
    assert df["class"].iloc[1] == eye["class"]
    assert math.isnan(df["refraction_D"].iloc[1])  # an elastic run has no refraction
    # An iterator's runs, collected.
    assert len(eyeshell.SweepResults(eyeshell.iter_sweep(small(), grid=GAMMA)).to_frame()) == 10


def test_to_frame_matches_the_command_lines_sweep_csv(cli, tmp_path):
    optional("pandas")
    cli("sweep", SCENES / "grow.toml", "--set", "solver.nodes=101", "--out", tmp_path / "s", "--quiet")
    import pandas
    table = pandas.read_csv(tmp_path / "s" / "sweep.csv")
    df = eyeshell.sweep(SCENES / "grow.toml", solver__nodes=101).to_frame()
    final = df[df["t"] == 1.0].reset_index(drop=True)
    assert list(final["run"]) == list(table["run"])
    for column in ["growth.Gamma", "growth.delta", "axial_length", "equatorial_radius",
                   "retina_minus_blue", "class"]:
        assert list(final[column]) == list(table[column]), column


# Grids in the caller's key order.

def test_a_grid_runs_in_the_callers_key_order():
    scene = eyeshell.Scene(solver__nodes=101)
    runs = eyeshell.sweep(scene, grid={"pressure.dP": [1, 2], "fibres.D": [0, 100]})
    assert [list(r.values.items()) for r in runs] == [
        [("pressure.dP", 1.0), ("fibres.D", 0.0)],
        [("pressure.dP", 1.0), ("fibres.D", 100.0)],
        [("pressure.dP", 2.0), ("fibres.D", 0.0)],
        [("pressure.dP", 2.0), ("fibres.D", 100.0)],
    ]
    assert [r.name for r in runs] == ["dP=1_D=0", "dP=1_D=100", "dP=2_D=0", "dP=2_D=100"]
    flipped = eyeshell.sweep(scene, grid={"fibres.D": [0, 100], "pressure.dP": [1, 2]})
    assert [r.name for r in flipped] == ["D=0_dP=1", "D=0_dP=2", "D=100_dP=1", "D=100_dP=2"]


def test_a_sweep_files_grid_runs_in_the_files_order(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text((SCENES / "const.toml").read_text()
                    + '\n[sweep.grid]\n"growth.delta" = [2, 6]\n"growth.Gamma" = [4, 8]\n')
    plan = eyeshell._eyeshell.expand_sweep(path.read_text(), str(path), [])
    assert [name for name, _, _ in plan] == ["delta=2_Gamma=4", "delta=2_Gamma=8", "delta=6_Gamma=4",
                                             "delta=6_Gamma=8"]


# A sweep file from Python: its scene alone, or its sweep replaced.

def test_a_sweep_files_scene_reads_without_its_sweep():
    with pytest.raises(eyeshell.InputError, match=r"Scene.from_file\(path, sweep=False\)"):
        eyeshell.Scene.from_file(SCENES / "grow.toml")
    base = eyeshell.Scene.from_file(SCENES / "grow.toml", sweep=False, solver__nodes=101)
    assert base.grows and base["fibres.D"] == 100.0 and base["solver.nodes"] == 101
    g = eyeshell.grow(base, frames=False)
    assert g.summary["status"] == "ok"
    with pytest.raises(TypeError, match="sweep must be True or False"):
        eyeshell.Scene.from_file(SCENES / "grow.toml", sweep="no")


def test_a_sweep_files_sweep_is_replaced_by_a_grid_or_runs():
    runs = eyeshell.sweep(SCENES / "grow.toml", grid={"growth.Gamma": [5]}, solver__nodes=101)
    assert [(r.name, r.values) for r in runs] == [("Gamma=5", {"growth.Gamma": 5.0})]
    assert runs[0].result.scene["fibres.D"] == 100.0  # the file's scene, without its grid
    runs = eyeshell.sweep(SCENES / "grow.toml", runs=[{"name": "one"}], solver__nodes=101)
    assert [r.name for r in runs] == ["one"]


# Keyword overrides set together, validated once.

def test_keyword_overrides_are_set_together_and_validated_once():
    g = eyeshell.grow(eyeshell.Scene(), growth__t_end=0.2, output__times=[0.2], solver__nodes=101)
    assert g.times == [0.0, 0.2] and g.summary["status"] == "ok"
    s = eyeshell.Scene(output__times=[0.2], growth__t_end=0.2)  # either order
    assert s["growth.t_end"] == 0.2
    s = eyeshell.Scene()
    s.update({"growth": {"t_end": 0.2}}, output__times=[0.1, 0.2])
    assert s["output.times"] == [0.1, 0.2]
    # Still checked, once all are set; a refused update leaves the scene as it was.
    with pytest.raises(eyeshell.InputError, match="0.5 is after growth.t_end = 0.2"):
        s.update(growth__t_end=0.2, output__times=[0.5])
    with pytest.raises(eyeshell.InputError, match="fibres.D = -1 must be non-negative"):
        s.update(fibres__D=-1, output__times=[0.2])
    assert s["output.times"] == [0.1, 0.2] and s["fibres.D"] == 0.0


# Errors in Python's terms.

COMMAND_LINE = ["--set", "--out", "--force", "--field", "--shard", "eyeshell sweep", "`eyeshell "]


@pytest.mark.parametrize(
    "make, needle",
    [
        (lambda: eyeshell.solve(SCENES / "grow.toml"), "run it with eyeshell.sweep()"),
        (lambda: eyeshell.grow(SCENES / "grow.toml"), "Scene.from_file(path, sweep=False)"),
        (lambda: eyeshell.sweep(SCENES / "grow.toml", growth__Gamma=3),
         "sweeps growth.Gamma: drop growth.Gamma=3 from the keyword overrides, or give its values in grid="),
        (lambda: eyeshell.sweep(eyeshell.Scene(), grid={"fibres.D": list(range(10001))}),
         "split it into eyeshell.sweep() calls of at most 10000 runs each"),
        (lambda: eyeshell.Scene(fibres__E=1), "set fibres.E=1: unknown key 'fibres.E'"),
        (lambda: eyeshell.sweep(eyeshell.Scene(), grid={"fibres.D": [1]}, fibres__E=1),
         "set fibres.E=1: unknown key 'fibres.E'"),
        (lambda: eyeshell.grow(SCENES / "const.toml", sensitivities=["growth.eta"]),
         "\"growth.eta\" is not a scene key (supported: "),
        (lambda: eyeshell.grow(SCENES / "const.toml", sensitivities=["growth.eta"]),
         "eyeshell.keys() lists every key"),
    ],
)
def test_errors_speak_python_not_the_command_line(make, needle):
    with pytest.raises(eyeshell.InputError) as e:
        make()
    message = str(e.value)
    assert needle in message, message
    assert not any(flag in message for flag in COMMAND_LINE), message


def test_the_command_line_keeps_its_own_wording(cli, tmp_path):
    r = cli("sweep", SCENES / "grow.toml", "--set", "growth.Gamma=3", "--out", tmp_path / "s", check=False)
    assert r.returncode == 2 and "remove `--set growth.Gamma=3`" in r.stderr
    r = cli("solve", SCENES / "grow.toml", "--out", tmp_path / "o", check=False)
    assert r.returncode == 2 and f"run it with `eyeshell sweep {SCENES / 'grow.toml'} --out DIR`" in r.stderr


def test_file_refusals_name_python_arguments(cli, tmp_path):
    scipy_io = optional("scipy.io")
    foreign = tmp_path / "theirs.mat"
    foreign.write_bytes(b"not eyeshell's")
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.solve(solver__nodes=101).to_mat(foreign)
    assert "refusing to overwrite it (force=True replaces it)" in str(e.value)
    assert "--force" not in str(e.value) and foreign.read_bytes() == b"not eyeshell's"
    eyeshell.solve(solver__nodes=101).to_mat(foreign, force=True)
    assert scipy_io.loadmat(foreign)["sol"][0, 0]["solver"][0] == "bvp4c"
    ref = tmp_path / "ref.mat"
    scipy_io.savemat(ref, {"sol": np.array([1.0, 2.0])})
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.compare(eyeshell.solve(solver__nodes=101), ref)
    assert 'field="NAME"' in str(e.value) and "--field" not in str(e.value)
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.compare(eyeshell.solve(solver__nodes=101), ref, field="other")
    assert str(e.value).startswith(f"{ref}: field=\"other\": no such variable"), str(e.value)


# compare() on results.

def test_compare_takes_solutions_and_growths(cli, tmp_path):
    sol = eyeshell.solve(SCENES / "default.toml", solver__nodes=201)
    cli("solve", SCENES / "default.toml", "--set", "solver.nodes=201", "--out", tmp_path / "run", "--quiet")
    same = eyeshell.compare(sol, tmp_path / "run")
    assert same.passed and same.text.startswith(f"{tmp_path / 'run' / 'fields.csv'} vs Solution: ")
    assert eyeshell.compare(tmp_path / "run", sol).passed
    stiffer = eyeshell.solve(SCENES / "default.toml", solver__nodes=201, fibres__D=50)
    differs = eyeshell.compare(stiffer, sol)
    assert not differs.passed and differs.pairs[0]["run"] == "Solution (run)"
    assert max(f["max_abs"] for f in differs.pairs[0]["fields"].values()) > 1e-3

    a = eyeshell.grow(small(), frames=False)
    b = eyeshell.grow(small(), frames=False, growth__Gamma=7)
    assert eyeshell.compare(a, a).passed
    assert [p["time"] for p in eyeshell.compare(a, a).pairs] == a.times
    c = eyeshell.compare(b, a)
    assert not c.passed and not [p for p in c.pairs[1:] if p["passed"]]  # every t > 0 differs
    assert c.pairs[1]["run"] == "Growth (run)/snapshot_00001_t0.100000.mat"
    assert c.pairs[1]["reference"] == "Growth (reference)/snapshot_00001_t0.100000.mat"
    with pytest.raises(TypeError, match="run must be a Solution, a Growth or a path"):
        eyeshell.compare(3, sol)


# Growth.to_mat: the published per-timestep layout, as `eyeshell export --mat` writes it.

def test_growth_to_mat_writes_what_the_command_lines_export_writes(cli, tmp_path):
    scipy_io = optional("scipy.io")
    cli("grow", SCENES / "const.toml", "--set", "solver.nodes=101", "--out", tmp_path / "run", "--quiet")
    cli("export", tmp_path / "run", "--mat", tmp_path / "cli")
    g = eyeshell.grow(SCENES / "const.toml", solver__nodes=101)
    files = g.to_mat(tmp_path / "py")
    names = sorted(p.name for p in (tmp_path / "cli").iterdir() if not p.name.startswith("."))
    # The snapshots in time order, then the series and history (each compared below, by value).
    assert sorted(f.rsplit("/", 1)[1] for f in files) == names and len(names) == 5 + 2
    assert [f.rsplit("/", 1)[1] for f in files][-2:] == ["series.mat", "history.mat"]
    for name in names:
        ours = scipy_io.loadmat(tmp_path / "py" / name)
        theirs = scipy_io.loadmat(tmp_path / "cli" / name)
        assert sorted(k for k in ours if not k.startswith("__")) == sorted(
            k for k in theirs if not k.startswith("__"))
        for k in theirs:
            if not k.startswith("__"):
                assert np.array_equal(ours[k], theirs[k], equal_nan=ours[k].dtype.kind == "f"), (name, k)
    assert scipy_io.loadmat(tmp_path / "py" / names[-1])["time"][0, 0] == 1.0
    # Written again over its own export; never into a directory eyeshell did not write.
    assert g.to_mat(tmp_path / "py") == files
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    with pytest.raises(eyeshell.InputError):
        g.to_mat(tmp_path / "mine")
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep"


def test_growth_to_mat_names_a_scene_in_years_by_age_as_the_command_line_does(cli, tmp_path):
    optional("scipy.io")
    sets = ["solver.nodes=51", "time.unit=years", "time.start=2", "time.end=12",
            "output.times=[3, 4, 6, 12]"]
    cli("grow", SCENES / "const.toml", *[a for kv in sets for a in ("--set", kv)],
        "--out", tmp_path / "run", "--quiet")
    cli("export", tmp_path / "run", "--mat", tmp_path / "cli")
    g = eyeshell.grow(SCENES / "const.toml", solver__nodes=51, time__unit="years",
                      time__start=2.0, time__end=12.0, output__times=[3.0, 4.0, 6.0, 12.0])
    files = [f.rsplit("/", 1)[1] for f in g.to_mat(tmp_path / "py")]
    names = sorted(p.name for p in (tmp_path / "cli").iterdir() if not p.name.startswith("."))
    assert sorted(files) == names and len(names) == 5 + 2
    assert "age" in files[-3] and "12" in files[-3], files


def test_solution_to_mat_is_the_command_lines_export(cli, tmp_path):
    scipy_io = optional("scipy.io")
    cli("solve", SCENES / "default.toml", "--set", "solver.nodes=101", "--out", tmp_path / "run", "--quiet")
    cli("export", tmp_path / "run", "--mat", tmp_path / "cli.mat")
    eyeshell.solve(SCENES / "default.toml", solver__nodes=101).to_mat(tmp_path / "py.mat")
    ours = scipy_io.loadmat(tmp_path / "py.mat")["sol"][0, 0]
    theirs = scipy_io.loadmat(tmp_path / "cli.mat")["sol"][0, 0]
    for k in ["x", "y", "yp", "sigma", "z", "h"]:
        assert np.array_equal(ours[k], theirs[k], equal_nan=ours[k].dtype.kind == "f"), k


# A fit's notes and table.

def test_a_fit_carries_the_reports_notes_and_table(cli, tmp_path):
    keys = ["growth.eta0", "growth.Gamma", "growth.delta"]
    start = {"growth.eta0": 60, "growth.Gamma": 9, "growth.delta": 3.5}
    r = eyeshell.fit(SCENES / "const.toml", DATA, fit=keys, solver__nodes=101, **start)
    assert len(r.notes) == 1
    assert r.notes[0].startswith("strongly correlated (|ρ| ≥ 0.99): growth.eta0 and growth.Gamma at -0.99")
    assert "give its value with a keyword override (section__key=value)" in r.notes[0], r.notes[0]
    assert "--set" not in r.notes[0] and "growth__" not in r.notes[0], r.notes[0]
    assert str(r) == r.text and f"  note             {r.notes[0]}\n" in r.text
    # The command line's table, but for its note's advice and the output line.
    sets = [a for k, v in start.items() for a in ("--set", f"{k}={v}")]
    printed = cli("fit", SCENES / "const.toml", "--data", DATA, "--fit", ",".join(keys), "--set",
                  "solver.nodes=101", *sets, "--out", tmp_path / "fit").stdout
    ours = [line for line in r.text.splitlines() if not line.lstrip().startswith(("note", "time"))]
    theirs = [line for line in printed.splitlines()
              if not line.lstrip().startswith(("note", "time", "output"))]
    assert ours[1:] == theirs[1:]
    row = next(line for line in r.text.splitlines() if line.lstrip().startswith("growth.Gamma"))
    estimate = f"{r.estimates['growth.Gamma']:.6f}"
    assert estimate in row and f"{r.standard_errors['growth.Gamma']:.6f}" in row
    one = eyeshell.fit(SCENES / "const.toml", DATA, fit=["growth.Gamma"], solver__nodes=101)
    assert one.notes == [] and "note" not in one.text


def test_to_mat_refuses_a_growth_whose_snapshots_were_broken(tmp_path):
    g = eyeshell.grow(small(), frames=False)
    t = g.times[-1]
    del g.snapshots[t]["eta"]
    with pytest.raises(eyeshell.InputError, match="to_mat: the snapshot at t = 1 has no column eta"):
        g.to_mat(tmp_path / "a")
    g = eyeshell.grow(small(), frames=False)
    nodes = len(g.snapshots[t]["Sigma"])
    g.snapshots[t]["r"] = g.snapshots[t]["r"][:-1]
    with pytest.raises(eyeshell.InputError, match=f"has {nodes - 1} values of r but {nodes} of Sigma"):
        g.to_mat(tmp_path / "a")
    assert not (tmp_path / "a").exists()  # nothing half-written
    with pytest.raises(TypeError, match="directory must be a path"):
        g.to_mat(5)
