"""Every kind of bad input raises InputError (the command line's exit 2) with the command
line's one-line message; a failed computation raises SolverError (exit 1)."""

import os
import pathlib
import shutil

import numpy as np
import pytest

import eyeshell
from conftest import ROOT, SCENES


@pytest.mark.parametrize(
    "make, needle",
    [
        (lambda: eyeshell.Scene(nonsense=1), "unknown key 'nonsense'"),
        (lambda: eyeshell.Scene(fibres__D=-1), "fibres.D = -1 must be non-negative"),
        (lambda: eyeshell.Scene({"solver": {"nodes": 10**11}}), "solver.nodes"),
        (lambda: eyeshell.Scene(solver__scheme="simpson"), "solver.scheme"),
        (lambda: eyeshell.Scene(fibres__D="stiff"), "fibres.D"),
        (lambda: eyeshell.Scene.from_file(SCENES / "missing.toml"), "missing.toml"),
        (lambda: eyeshell.Scene.from_file(SCENES / "grow.toml"), "[sweep]"),
        (lambda: eyeshell.Scene.from_toml("[fibres\nD = 1"), "<string>"),
        (lambda: eyeshell.solve(pressure__dP=1e3), "ΔP"),
        (lambda: eyeshell.grow(eyeshell.Scene()), "no [growth] section"),
        (lambda: eyeshell.solve(solver__nodes=101).at(1e6), "outside the shell"),
        (lambda: eyeshell.sweep(eyeshell.Scene(), grid={"fibres.D": [0, -5]}), "fibres.D"),
        (lambda: eyeshell.sweep(SCENES / "grow.toml", jobs=0), "jobs"),
        (lambda: eyeshell.compare(SCENES / "nowhere", SCENES / "default.toml"), "nowhere"),
        (lambda: eyeshell.compare(SCENES, SCENES, tol=-1), "tol = -1"),
    ],
)
def test_bad_input_is_an_input_error(make, needle):
    with pytest.raises(eyeshell.InputError) as e:
        make()
    message = str(e.value)
    assert needle in message and "\n" not in message
    assert isinstance(e.value, eyeshell.EyeshellError)


def test_the_message_is_the_command_lines(cli, tmp_path):
    r = cli("solve", SCENES / "default.toml", "--set", "pressure.dP=1e3", "--out", tmp_path / "o",
            check=False)
    assert r.returncode == 2
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.solve(SCENES / "default.toml", pressure__dP=1e3)
    # The same line but for where the value came from: `--set` there, the keyword here
    # (not the scene file, which did not set it).
    cli_where, cli_what = r.stderr.strip().removeprefix("eyeshell: error: ").split(": ", 1)
    where, what = str(e.value).split(": ", 1)
    assert (cli_where, where) == ("--set pressure.dP=1e3", "set pressure.dP=1000.0")
    assert what == cli_what


@pytest.mark.parametrize(
    "overrides, needle",
    [
        ({"solver.max_newton": 1, "fibres.D": 400}, "Newton did not converge"),
        ({"solver.max_seconds": 1e-9}, "solver.max_seconds"),
    ],
)
def test_a_failed_solve_is_a_solver_error(cli, tmp_path, overrides, needle):
    with pytest.raises(eyeshell.SolverError) as e:
        eyeshell.solve(SCENES / "fibres-nonuniform.toml", **overrides)
    assert needle in str(e.value) and not isinstance(e.value, eyeshell.InputError)
    sets = [a for k, v in overrides.items() for a in ("--set", f"{k}={v}")]
    r = cli("solve", SCENES / "fibres-nonuniform.toml", *sets, "--out", tmp_path / "o", check=False)
    assert r.returncode == 1


def test_a_failed_growth_is_a_solver_error():
    with pytest.raises(eyeshell.SolverError, match="growth failed at t = "):
        eyeshell.grow(SCENES / "const.toml", solver__max_seconds=0.05, solver__rtol=1e-12,
                      solver__nodes=2001)


def test_a_failed_run_of_a_sweep_is_recorded_and_the_others_go_on():
    runs = eyeshell.sweep(eyeshell.Scene(fibres__D=400, solver__nodes=101),
                          grid={"solver.max_newton": [1, 50]}, jobs=2)
    assert [r.status for r in runs] == ["failed", "ok"]
    assert "Newton did not converge" in runs[0].error and runs[0].result is None
    assert runs[1].result.summary["newton_iterations"] > 1


# Integer keys take any integral number; floats (even whole ones) are refused, as in a
# scene file and `--set`.


@pytest.mark.parametrize(
    "value",
    [301, np.int64(301), np.int32(301), np.uint16(301), np.array(301), np.array(301, dtype=np.int16)],
    ids=["int", "int64", "int32", "uint16", "0-d int64", "0-d int16"],
)
def test_an_integer_key_takes_any_integral_number(value):
    s = eyeshell.Scene(solver__nodes=value)
    assert s["solver.nodes"] == 301 and type(s["solver.nodes"]) is int
    assert eyeshell.Scene({"output": {"history_points": value}})["output.history_points"] == 301


def test_an_integral_object_of_another_library_is_an_integer():
    class Count:
        def __index__(self):
            return 301

    assert eyeshell.Scene(solver__nodes=Count())["solver.nodes"] == 301


@pytest.mark.parametrize(
    "value, needle",
    [
        (301.0, "must be an integer, found float 301"),
        (np.float64(301.0), "must be an integer, found float 301"),
        (np.array(301.0), "must be an integer, found float 301"),
        (np.float32(301.5), "must be an integer, found float 301.5"),
        (True, "must be an integer, found boolean true"),
        (np.True_, "must be an integer, found boolean true"),
        ("301", "must be an integer, found string"),
        (np.array([301]), "must be an integer, found an array"),
        (10**30, "beyond TOML's 64 bits"),
        (np.uint64(2**64 - 1), "beyond TOML's 64 bits"),
        (-1, "solver.nodes"),
        (np.int64(-1), "solver.nodes"),
    ],
    ids=lambda v: repr(v),
)
def test_an_integer_key_refuses_what_is_not_integral(value, needle):
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.Scene(solver__nodes=value)
    assert needle in str(e.value) and "\n" not in str(e.value)


def test_numpy_values_for_float_and_bool_keys():
    s = eyeshell.Scene(fibres__D=np.float32(2.5), pressure__dP=np.array(2.0),
                       material__C=np.int64(3), solver__pole_grading=np.False_)
    assert (s["fibres.D"], s["pressure.dP"], s["material.C"]) == (2.5, 2.0, 3.0)
    assert s["solver.pole_grading"] is False
    s = eyeshell.Scene(output__times=np.array([0.25, 0.5]))
    assert s["output.times"] == [0.25, 0.5]
    with pytest.raises(TypeError, match="not bytes"):
        eyeshell.Scene(name=b"sphere")
    with pytest.raises(TypeError, match="not complex"):
        eyeshell.Scene(fibres__D=np.complex128(1))


def test_a_sweep_takes_numpy_values_for_its_grid_and_overrides():
    scene = eyeshell.Scene.from_file(SCENES / "default.toml")
    runs = eyeshell.sweep(scene, grid={"solver.nodes": np.arange(101, 302, 100)},
                          pressure__dP=np.float64(2.5), solver__max_newton=np.int64(40))
    assert [r.name for r in runs] == ["nodes=101", "nodes=201", "nodes=301"]
    assert [r.result.scene["solver.nodes"] for r in runs] == [101, 201, 301]
    assert all(r.result.scene["solver.max_newton"] == 40 for r in runs)
    with pytest.raises(eyeshell.InputError, match="must be an integer, found float 101"):
        eyeshell.sweep(scene, grid={"solver.nodes": np.linspace(101, 301, 3)})
    with pytest.raises(eyeshell.InputError, match="grid: solver.nodes: give a list of values"):
        eyeshell.sweep(scene, grid={"solver.nodes": np.int64(101)})
    with pytest.raises(eyeshell.InputError, match="jobs = 1.0: must be a whole number"):
        eyeshell.sweep(scene, grid={"solver.nodes": [101]}, jobs=1.0)
    with pytest.raises(eyeshell.InputError, match="jobs = True: must be a whole number"):
        eyeshell.sweep(scene, grid={"solver.nodes": [101]}, jobs=True)
    # Each job is a process: as many as `eyeshell sweep --jobs` allows.
    with pytest.raises(eyeshell.InputError, match="jobs = 1025: must be a whole number from 1 to 1,024"):
        eyeshell.sweep(scene, grid={"solver.nodes": [101]}, jobs=1025)
    assert len(eyeshell.sweep(scene, grid={"solver.nodes": [101]}, jobs=np.int64(1))) == 1


# Paths: a str, bytes or os.PathLike (of either) everywhere a file is named, as the
# messages say.

class BytesPath:
    def __init__(self, path):
        self.path = os.fsencode(path)

    def __fspath__(self):
        return self.path


PATH_KINDS = [str, os.fsencode, pathlib.Path, BytesPath]


@pytest.mark.parametrize("kind", PATH_KINDS, ids=["str", "bytes", "Path", "PathLike of bytes"])
def test_every_kind_of_path_names_a_file(kind, tmp_path):
    default = SCENES / "default.toml"
    sol = eyeshell.solve(kind(default), solver__nodes=101)
    assert sol.scene["solver.nodes"] == 101 and sol.summary["residual_norm"] < 1e-8
    assert eyeshell.Scene.from_file(kind(default)) == eyeshell.Scene.from_file(default)
    r = eyeshell.fit(kind(SCENES / "const.toml"), kind(ROOT / "examples" / "fit" / "const_synthetic.csv"),
                     fit=["growth.Gamma"], solver__nodes=101, max_iterations=1)
    assert r.report["data"]["observations"] > 0
    sweep = eyeshell.sweep(kind(SCENES / "grow.toml"), solver__nodes=101, jobs=2)
    assert len(sweep) > 1 and all(r.ok for r in sweep)


def test_a_file_name_that_is_not_utf8_reaches_the_file_system(tmp_path):
    odd = os.fsencode(tmp_path) + b"/scene-\xff.toml"
    with open(odd, "wb") as f:
        f.write(b"[solver]\nnodes = 101\n")
    assert eyeshell.solve(odd).scene["solver.nodes"] == 101


@pytest.mark.parametrize("call", [
    lambda: eyeshell.solve(5),
    lambda: eyeshell.grow(3.5),
    lambda: eyeshell.Scene.from_file(5),
    lambda: eyeshell.compare(5, SCENES),
    lambda: eyeshell.fit(SCENES / "const.toml", 5, fit=["growth.Gamma"]),
])
def test_what_is_not_a_path_is_refused_saying_what_a_path_is(call):
    with pytest.raises(TypeError, match=r"a str, bytes or os.PathLike"):
        call()


# Sensitivity error control without sensitivities does nothing: refused, as on the
# command line.

@pytest.mark.parametrize("sensitivities", [(), [], ""])
def test_error_control_without_sensitivities_is_refused(cli, tmp_path, sensitivities):
    with pytest.raises(eyeshell.InputError, match="sensitivity error control needs sensitivities"):
        eyeshell.grow(SCENES / "const.toml", sensitivities=sensitivities,
                      sensitivity_error_control=True)
    r = cli("grow", SCENES / "const.toml", "--sensitivity-error-control", "--out", tmp_path / "g",
            check=False)
    assert r.returncode == 2 and not (tmp_path / "g").exists()
    with pytest.raises(TypeError, match="must be True or False, not str"):
        eyeshell.grow(SCENES / "const.toml", sensitivities=["growth.eta0"],
                      sensitivity_error_control="no")


# compare's docstring names what it compares: every kind it lists is compared, and a CSV
# file (which it says is not a reference) is refused.

def test_compare_takes_what_its_docstring_lists_and_refuses_csv(cli, tmp_path):
    doc = eyeshell.compare.__doc__
    assert "a CSV file is not a reference" in doc
    assert ".csv" not in doc
    run = tmp_path / "run"
    cli("solve", SCENES / "default.toml", "--set", "solver.nodes=101", "--out", run, "--quiet")
    cli("export", run, "--mat", tmp_path / "r.mat", "--npz", tmp_path / "r.npz")
    refs = tmp_path / "refs"
    refs.mkdir()
    shutil.copy(tmp_path / "r.mat", refs / "a.mat")
    shutil.copy(tmp_path / "r.npz", refs / "b.npz")
    for reference in [tmp_path / "r.mat", tmp_path / "r.npz", refs, run]:
        c = eyeshell.compare(run, reference)
        assert c.passed and len(c.pairs) >= 1, reference
    assert eyeshell.compare(tmp_path / "r.npz", run).passed  # an export as the run
    with pytest.raises(eyeshell.InputError, match="fields.csv"):
        eyeshell.compare(run, run / "fields.csv")


# Every exception carries what it is about: the key (or argument, column, file), the value
# as it was given and where it came from, None where the error names none; a SolverError
# its stage.


def attributes(e):
    return (e.value.key, e.value.value, e.value.origin, e.value.stage)


def test_a_bad_key_through_the_scene_names_it_and_its_keyword():
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.Scene(fibres__Dx=1)
    assert attributes(e) == ("fibres.Dx", None, "set fibres.Dx=1", None)
    assert str(e.value) == "set fibres.Dx=1: unknown key 'fibres.Dx' (did you mean 'fibres.D'?)"
    s = eyeshell.Scene()
    with pytest.raises(eyeshell.InputError) as e:
        s.set("fibres.D", -1)
    assert attributes(e) == ("fibres.D", "-1", "set fibres.D=-1", None)
    assert s["fibres.D"] == 0.0


def test_a_bad_value_in_a_scene_file_has_the_file_as_its_origin(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[fibres]\nD = -3\n")
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.Scene.from_file(path)
    assert attributes(e) == ("fibres.D", "-3", str(path), None)
    assert str(e.value) == f"{path}: fibres.D = -3 must be non-negative"
    # The keyword given on that file is the origin of its own value, the file of the rest.
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.solve(SCENES / "default.toml", pressure__dP=1e3)
    assert attributes(e)[:3] == ("pressure.dP", "1000", "set pressure.dP=1000.0")


def test_a_long_value_is_shortened():
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.Scene(solver__scheme="x" * 500)
    assert e.value.key == "solver.scheme"
    # As the scene's message shows it: quoted as TOML writes it, cut at 60 characters.
    assert e.value.value == '"' + "x" * 60 + '…"'
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.sweep(eyeshell.Scene(), grid={"fibres.D": "9" * 500})
    assert attributes(e) == ("fibres.D", "9" * 80 + "…", "argument", None)


def test_a_bad_keyword_argument_names_the_argument():
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.sweep(SCENES / "grow.toml", jobs=0)
    assert attributes(e) == ("jobs", "0", "argument", None)
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.compare(SCENES, SCENES, tol=-1)
    assert attributes(e) == ("tol", "-1", "argument", None)
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.sweep(eyeshell.Scene(), grid={"fibres.D": 5})
    assert attributes(e) == ("fibres.D", "5", "argument", None)


def test_a_bad_value_in_a_data_file_names_its_column_and_the_file(tmp_path):
    path = tmp_path / "data.csv"
    path.write_text("t,axial_length\n0.5,-2\n")
    with pytest.raises(eyeshell.InputError) as e:
        eyeshell.fit(SCENES / "const.toml", path, fit=["growth.Gamma"])
    assert attributes(e) == ("axial_length", "-2", str(path), None)


def test_a_failed_solve_names_its_stage_and_no_key():
    with pytest.raises(eyeshell.SolverError) as e:
        eyeshell.solve(SCENES / "fibres-nonuniform.toml", solver__max_newton=1, fibres__D=400)
    assert attributes(e) == (None, None, None, "solve")
    assert str(e.value).startswith("Newton did not converge")


def test_an_error_raised_without_attributes_has_them_as_none():
    e = eyeshell.InputError("x")
    assert (e.key, e.value, e.origin, e.stage) == (None, None, None, None)
    assert eyeshell.SolverError.key is None and eyeshell.EyeshellError.origin is None
