"""eyeshell.grow against the command line's run directory, bit for bit, and its progress."""

import math
import numpy as np
import pytest

import eyeshell
from conftest import SCENES, optional, read_csv


def test_the_const_scene_matches_the_command_lines_series(cli, tmp_path):
    cli("grow", SCENES / "const.toml", "--out", tmp_path / "run", "--quiet")
    g = eyeshell.grow(SCENES / "const.toml", frames=False)
    run = tmp_path / "run"
    for name, table in [("series.csv", g.series), ("history.csv", g.history)]:
        written = read_csv(run / name)
        assert list(written) == list(table), name
        for column, values in written.items():
            got = list(np.asarray(table[column]))
            # NaN where a quantity is not computed (defocus_D without a defocus rule) on both sides.
            same = [a == b or (isinstance(b, float) and math.isnan(b) and math.isnan(a)) for a, b in zip(got, values)]
            assert len(got) == len(values) and all(same), (name, column)
    assert len(g.history["t"]) > len(g.series["t"]) > 2  # const records 100 history points
    files = sorted((run / "snapshots").iterdir())
    assert len(files) == len(g.snapshots)
    for path, (t, fields) in zip(files, g.snapshots.items()):
        written = read_csv(path)
        assert f"_t{t:.6f}" in path.name and list(written) == list(fields)
        for column, values in written.items():
            assert np.array_equal(np.array(values), fields[column], equal_nan=True), (path.name, column)
    import json

    summary = json.loads((run / "summary.json").read_text())
    for k in ["final", "snapshots", "status", "steps", "newton_iterations", "parameters"]:
        assert g.summary[k] == summary[k], k


def test_progress_is_called_after_every_step_in_time_order():
    seen = []
    g = eyeshell.grow(SCENES / "const.toml", progress=lambda t, t_end: seen.append((t, t_end)),
                      frames=False, solver__nodes=101)
    ts = [t for t, _ in seen]
    assert len(ts) == g.summary["steps"] and ts == sorted(ts) and ts[-1] == 1.0
    assert {t_end for _, t_end in seen} == {1.0}


def test_an_exception_in_progress_stops_the_run_and_is_raised():
    calls = []

    def stop(t, t_end):
        calls.append(t)
        if len(calls) == 3:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        eyeshell.grow(SCENES / "const.toml", progress=stop)
    assert len(calls) == 3


def test_progress_true_draws_a_bar_on_stderr(capfd):
    eyeshell.grow(SCENES / "const.toml", progress=True, frames=False, solver__nodes=101)
    err = capfd.readouterr().err
    assert "t = 1.0000 / 1" in err and err.endswith("\n")


def test_peripheral_refraction_per_field_at_each_snapshot():
    g = eyeshell.grow(SCENES / "const.toml", frames=False, solver__nodes=101)
    p = g.peripheral
    assert list(p) == ["t", "field_deg", "refraction_D", "relative_D"]
    fields = [0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0]
    assert len(p["t"]) == len(g.series["t"]) * len(fields)
    assert list(p["field_deg"][:9]) == fields and list(p["t"][:9]) == [0.0] * 9
    # Field 0 is the pole: its refraction is the series' refraction_D (a coarser table).
    pole = p["refraction_D"][p["field_deg"] == 0.0]
    assert np.allclose(pole, g.series["refraction_D"], atol=1e-3)
    assert np.all(p["relative_D"][p["field_deg"] == 0.0] == 0.0)
    # NaN where a wide field of the +10 D eye at t = 0 has no refraction, in both columns.
    assert np.allclose(p["relative_D"], p["refraction_D"] - np.repeat(pole, 9), equal_nan=True)
    assert np.all(np.isfinite(p["refraction_D"][p["field_deg"] <= 30.0]))


def test_peripheral_through_the_lenses_is_the_files(cli, tmp_path):
    # A dual-focus contact lens: every snapshot's naked rows, then each image's rows through
    # the lens with its power and share, as the command line's peripheral.csv has them.
    sets = {"solver.nodes": 41, "output.times": "[0.5, 1.0]", "output.history_points": 0}
    g = eyeshell.grow(SCENES / "eyewear" / "dual-focus.toml", frames=False,
                      **{k.replace(".", "__"): v for k, v in sets.items() if k != "output.times"},
                      output__times=[0.5, 1.0])
    args = [a for k, v in sets.items() for a in ("--set", f"{k}={v}")]
    cli("grow", SCENES / "eyewear" / "dual-focus.toml", *args, "--out", tmp_path / "run", "-q")
    file = read_csv(tmp_path / "run" / "peripheral.csv")
    p = g.peripheral
    assert list(p) == list(file), (list(p), list(file))
    assert list(p["through"]) == file["through"] and set(file["through"]) == {"naked", "lenses"}
    assert [int(i) for i in p["image"]] == [int(i) for i in file["image"]]
    for c in ["t", "field_deg", "refraction_D", "relative_D", "share"]:
        assert np.array_equal(p[c], np.array(file[c], dtype=float), equal_nan=True), c
    powers = [math.nan if x == "" else x for x in file["image_power_D"]]
    assert np.array_equal(p["image_power_D"], np.array(powers, dtype=float), equal_nan=True)
    # Through the lens the two images' shares sum to 1 at every time and field.
    lens = p["through"] == "lenses" if isinstance(p["through"], np.ndarray) else np.array(p["through"]) == "lenses"
    for t in set(p["t"]):
        for f in set(p["field_deg"]):
            at = lens & (p["t"] == t) & (p["field_deg"] == f)
            assert abs(p["share"][at].sum() - 1.0) < 1e-12, (t, f)


def test_series_are_data_frames_with_pandas():
    pandas = optional("pandas")
    g = eyeshell.grow(SCENES / "const.toml", solver__nodes=101)
    assert isinstance(g.series, pandas.DataFrame)
    assert list(g.series.columns) == ["t", "axial_length", "equatorial_radius",
                                      "retina_minus_blue", "retina_minus_red", "class", "refraction_D",
                                      "drive", "defocus_D"]
    assert g.series["class"].iloc[-1] == g.summary["final"]["class"]
    plain = eyeshell.grow(SCENES / "const.toml", frames=False, solver__nodes=101)
    assert np.array_equal(g.series["axial_length"].to_numpy(), plain.series["axial_length"])


def test_grow_tol_delivers_and_estimates_the_error_it_reports():
    # tol = 1e-3 on the const scene: N and rtol chosen, the estimate within tol, and the
    # true error (against N = 201 at rtol 1e-7, itself within 5e-6 mm of IDA at N = 3201,
    # rtol 1e-10: BENCHMARKS.md) within tol and within [1/3, 30] of the estimate.
    g = eyeshell.grow(SCENES / "const.toml", frames=False, tol=1e-3)
    assert g.summary["accuracy"]["tol"] == 1e-3
    assert g.summary["accuracy"]["nodes"] != 501  # chosen, not the scene's solver.nodes
    est = g.error_estimate
    assert set(est["axial_length"]) == {"total", "space", "time"}
    assert 0 < est["axial_length"]["total"] <= 1e-3
    # Every recorded time has its estimate: the snapshots' and history.csv's.
    assert set(g.series["t"]) <= {row["t"] for row in est["per_time"]}
    assert len(est["per_time"]) > len(g.series["t"])
    ref = eyeshell.grow(SCENES / "const.toml", frames=False, solver__nodes=201,
                        solver__rtol=1e-7, solver__atol=1e-9)
    for name in ["axial_length", "equatorial_radius"]:
        error = np.max(np.abs(np.asarray(g.series[name]) - np.asarray(ref.series[name])))
        assert error <= 1e-3, name
        assert error / 3 <= est[name]["total"] <= 30 * error, (name, error, est[name])
    assert ref.error_estimate is None


def test_grow_tol_is_solver_tol():
    a = eyeshell.grow(SCENES / "const.toml", frames=False, tol=1e-3)
    b = eyeshell.grow(SCENES / "const.toml", frames=False, solver__tol=1e-3)
    assert list(a.series["axial_length"]) == list(b.series["axial_length"])
    assert a.error_estimate == b.error_estimate


@pytest.mark.parametrize("tol", [0.0, -1e-4, float("nan"), float("inf")])
def test_grow_tol_refuses_what_is_not_a_tolerance(tol):
    with pytest.raises(eyeshell.InputError, match="solver.tol"):
        eyeshell.grow(SCENES / "const.toml", tol=tol)


def test_grow_tol_and_solver_tol_together_is_refused():
    with pytest.raises(TypeError, match="both tol and solver__tol"):
        eyeshell.grow(SCENES / "const.toml", tol=1e-3, solver__tol=1e-4)


def test_growth_to_a_tolerance_reads_its_thread_count_from_the_environment(monkeypatch):
    """EYESHELL_JOBS, as for `eyeshell grow`: the rounds' threads, recorded in the summary,
    the same series bit for bit, and a bad count refused in one line."""
    runs = {}
    for jobs in ["1", "2"]:
        monkeypatch.setenv("EYESHELL_JOBS", jobs)
        g = eyeshell.grow(SCENES / "const.toml", solver__tol=1e-3)
        assert g.summary["accuracy"]["threads"] == int(jobs)
        runs[jobs] = np.asarray(g.series["axial_length"])
    assert np.array_equal(runs["1"], runs["2"])
    monkeypatch.setenv("EYESHELL_JOBS", "0")
    with pytest.raises(eyeshell.InputError, match="EYESHELL_JOBS") as e:
        eyeshell.grow(SCENES / "const.toml", solver__tol=1e-3)
    assert "\n" not in str(e.value)
    assert (e.value.key, e.value.value, e.value.origin) == ("EYESHELL_JOBS", "0", "EYESHELL_JOBS")
