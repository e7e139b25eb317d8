"""Every kind of bad input raises InputError (the command line's exit 2) with the command
line's one-line message; a failed computation raises SolverError (exit 1)."""

import pytest

import eyeshell
from conftest import SCENES


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
    # The same line but for where the value came from: `--set` there, the scene here.
    cli_where, cli_what = r.stderr.strip().removeprefix("eyeshell: error: ").split(": ", 1)
    where, what = str(e.value).split(": ", 1)
    assert (cli_where, where) == ("--set pressure.dP=1e3", str(SCENES / "default.toml"))
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
