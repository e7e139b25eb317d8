"""Growth rules written in Python: eyeshell.grow(scene, stimulus=f) (docs/guide/python.md,
"Rules in Python"): the paper's rule written in Python against the built-in one, the
partials (differenced or given), and every way a rule can be wrong."""

import re
import textwrap

import numpy as np
import pytest

import eyeshell
from conftest import SCENES
from test_threads import interrupt

CONST = str(SCENES / "const.toml")
# A small, quick run for the refusals.
SMALL = {"solver__nodes": 51, "frames": False}


def papers(s):
    return np.maximum(s.depth_mm, 0)


def test_the_papers_rule_in_python_reproduces_the_built_in_run():
    # The const scene as published (501 nodes) at rtol 1e-8. The differences of a rule that
    # is linear on either side of its kink are exact (±h over 2h) but within a step of the
    # kink, so the run is the built-in one's arithmetic: bit for bit here, 1e-5 mm promised.
    builtin = eyeshell.grow(CONST, frames=False, solver__rtol=1e-8)
    python = eyeshell.grow(CONST, frames=False, solver__rtol=1e-8, stimulus=papers)
    a, b = builtin.series["axial_length"], python.series["axial_length"]
    assert len(a) == len(b) == 5 and a[-1] - a[0] > 0.5
    assert np.max(np.abs(a - b)) <= 1e-5, (a, b)
    assert python.rule["name"] == "python:papers" and python.rule["calls"] > 100
    assert builtin.rule is None
    # The run's outputs carry the Python rule's drive, as the built-in run's do.
    assert np.array_equal(builtin.series["retina_minus_blue"], python.series["retina_minus_blue"])


@pytest.mark.parametrize("integrator, keys", [("cvode", {}), ("euler", {"solver__steps": 50})])
def test_every_integrator_runs_a_python_rule(integrator, keys):
    # CVODE and Euler read the drive's values only: the built-in run's arithmetic.
    kw = {**SMALL, "solver__integrator": integrator, **keys}
    builtin = eyeshell.grow(CONST, **kw)
    python = eyeshell.grow(CONST, stimulus=papers, **kw)
    assert np.array_equal(builtin.series["axial_length"], python.series["axial_length"])


def test_a_python_rule_has_the_built_in_sensitivities():
    # IDAS's sensitivities use the rule's partials. Written without the positive part (the
    # engine takes it), the paper's rule is the built-in one, sensitivities bit for bit;
    # with np.maximum the points behind the surface have drive 0 and partial 0 instead of a
    # negative drive of slope 1, which moves the sensitivities by their own error (4e-4
    # relative here without error control, as grow()'s docstring says of IDAS's).
    kw = {**SMALL, "sensitivities": ["growth.eta0", "growth.Gamma"]}
    builtin = eyeshell.grow(CONST, **kw)
    linear = eyeshell.grow(CONST, stimulus=lambda s: s.depth_mm, **kw)
    clipped = eyeshell.grow(CONST, stimulus=papers, **kw)
    b = builtin.sensitivities["d_axial_length"]
    assert np.max(np.abs(b)) > 0.04
    assert np.array_equal(b, linear.sensitivities["d_axial_length"])
    np.testing.assert_allclose(clipped.sensitivities["d_axial_length"], b, rtol=0, atol=1e-3 * np.max(np.abs(b)))


def test_a_python_rule_runs_on_several_threads_under_a_tolerance(monkeypatch):
    # solver.tol runs several growths at once on EYESHELL_JOBS threads: the rule is called
    # from threads other than Python's own, each taking the GIL, and gives the built-in run.
    import threading

    monkeypatch.setenv("EYESHELL_JOBS", "2")
    threads = set()

    def rule(s):
        threads.add(threading.get_ident())
        return s.depth_mm

    builtin = eyeshell.grow(CONST, frames=False, tol=1e-3)
    python = eyeshell.grow(CONST, frames=False, tol=1e-3, stimulus=rule)
    assert np.array_equal(builtin.series["axial_length"], python.series["axial_length"])
    assert len(threads) == 2, threads


def test_the_view_is_what_the_docs_say():
    seen = []

    def rule(s):
        seen.append({k: getattr(s, k) for k in dir(s)})
        return np.maximum(s.depth_mm, 0)

    eyeshell.grow(CONST, growth__t_end=0.1, output__times=[0.1], stimulus=rule, **SMALL)
    first = seen[0]
    assert sorted(first) == sorted(
        ["t", "n", "sigma", "z", "r", "angle", "depth_mm", "depth_red_mm", "defocus_D"]
    )
    n = first["n"]
    assert isinstance(first["t"], float) and first["t"] == 0.0
    for k in ["sigma", "z", "r", "angle", "depth_mm", "depth_red_mm", "defocus_D"]:
        a = first[k]
        assert a.shape == (n,) and a.dtype == np.float64 and np.all(np.isfinite(a)), k
    # Σ in [ε, L], the pole among the points; the retina inside the shell (r < R0 =
    # 10 mm); red 0.655 mm behind blue; the polar angle 0 at the pole.
    lo, hi = eyeshell.Scene.from_file(CONST).span
    assert first["sigma"].min() == pytest.approx(lo) and first["sigma"].max() <= hi + 1e-12
    assert np.all(first["r"] < 10.0)
    np.testing.assert_allclose(first["depth_red_mm"] - first["depth_mm"], 0.655, atol=0.05)
    assert abs(first["angle"][np.argmin(first["sigma"])]) < 0.05
    # The defocus in dioptres has the depth's sign (an image behind the retina: hyperopic).
    front = np.abs(first["depth_mm"]) > 0.05
    assert np.all(np.sign(first["defocus_D"][front]) == np.sign(first["depth_mm"][front]))
    assert max(v["t"] for v in seen) == pytest.approx(0.1)


def test_given_partials_are_the_differences():
    # The drive d · cos(angle) reads the angle, whose partial the engine composes with the
    # angle's gradient in the retina's place: given exactly, the run is the differenced one.
    calls = {"differenced": 0, "given": 0}

    def differenced(s):
        calls["differenced"] += 1
        return s.depth_mm * np.cos(s.angle)

    def given(s):
        calls["given"] += 1
        c = np.cos(s.angle)
        return s.depth_mm * c, {"depth_mm": c, "angle": -s.depth_mm * np.sin(s.angle)}

    def wrong(s):
        # No partial in the angle: a Jacobian short of one term.
        return s.depth_mm * np.cos(s.angle), {"depth_mm": np.cos(s.angle)}

    runs = [eyeshell.grow(CONST, solver__rtol=1e-8, stimulus=f, **SMALL) for f in (differenced, given, wrong)]
    a = [g.series["axial_length"] for g in runs]
    # Two Jacobians equal to rounding: the same run to the integrator's rtol (1e-8).
    np.testing.assert_allclose(a[0], a[1], rtol=1e-7)
    # The same Newton history for the exact partials and the differences; the angle's term
    # matters (dropping it changes the iterations), so it is composed, not ignored.
    iters = [g.summary["nonlinear_iterations"] for g in runs]
    assert abs(iters[0] - iters[1]) <= 0.02 * iters[0], iters
    assert iters[2] != iters[0], iters
    # With the partials given, one call of f per evaluation; differenced, 4 more (two
    # quantities read, two signs) for each evaluation with partials.
    assert calls["given"] == runs[1].rule["calls"], calls
    assert calls["differenced"] > runs[0].rule["calls"] + 4 * 10, (calls, runs[0].rule)
    assert (calls["differenced"] - runs[0].rule["calls"]) % 4 == 0, calls


def test_a_constant_rule_may_return_a_scalar():
    g = eyeshell.grow(CONST, stimulus=lambda s: 0.0, **SMALL)
    a = g.series["axial_length"]
    # No drive, no growth: the eye stays as it was loaded.
    assert np.max(np.abs(a - a[0])) < 1e-9, a


def raised(f, match, kind=eyeshell.InputError, **keys):
    with pytest.raises(kind) as info:
        eyeshell.grow(CONST, stimulus=f, **{**SMALL, **keys})
    message = str(info.value)
    assert "\n" not in message and re.search(match, message), message
    return info.value


def test_a_rule_that_raises_is_named_with_its_exception():
    def bad(s):
        raise ValueError("no such hypothesis")

    e = raised(bad, r"^the growth rule python:.*bad raised ValueError: no such hypothesis$")
    assert isinstance(e.__cause__, ValueError)
    # A quantity the view does not have, in the view's own words.
    raised(lambda s: s.defocus, r"python:<lambda> raised AttributeError: the view of the retina has no 'defocus': it has t, n, sigma")


def test_a_rule_that_returns_nan_or_inf_is_refused_at_its_point():
    raised(lambda s: np.full(s.n, np.nan), r"^the growth rule python:<lambda> returned g_v = nan at Σ = 0\.\d{6} mm \(point 0 of \d+\): give finite numbers$")

    def inf_at_the_rim(s):
        g = np.maximum(s.depth_mm, 0)
        g[-1] = np.inf
        return g

    raised(inf_at_the_rim, r"returned g_v = inf at Σ = \d+\.\d{6} mm \(point (\d+) of \d+\)")
    # In a given partial too.
    raised(lambda s: (s.depth_mm, {"depth_mm": np.full(s.n, np.nan)}), r"returned the partial in depth_mm = nan at Σ")


def test_a_rule_of_the_wrong_shape_or_type_is_refused():
    raised(lambda s: s.depth_mm[:-1], r"returned g_v of shape \((\d+),\): give an array of (\d+) numbers")
    raised(lambda s: s.depth_mm[:, None], r"returned g_v of shape \(\d+, 1\)")
    raised(lambda s: "0.1", r"returned g_v of str: give an array")
    raised(lambda s: None, r"returned g_v of NoneType")
    raised(lambda s: s.depth_mm.astype(complex), r"returned g_v of dtype complex128")
    raised(lambda s: [object()] * s.n, r"returned g_v of list")
    raised(lambda s: (s.depth_mm, {"depth": 1.0}), r"gave a partial in 'depth': the partials are in depth_mm, depth_red_mm, defocus_D, z, r, angle")
    raised(lambda s: (s.depth_mm, 1.0, 2.0), r"returned a tuple of 3: return g, or \(g, \{quantity: partial\}\)")
    with pytest.raises(TypeError, match="stimulus must be a growth rule, a callable"):
        eyeshell.grow(CONST, stimulus=0.3, **SMALL)


def test_a_rule_needs_a_growing_scene():
    with pytest.raises(eyeshell.InputError, match="a growth rule needs a growing scene"):
        eyeshell.grow(eyeshell.Scene(), stimulus=papers, frames=False)


def test_a_slow_rule_is_stopped_by_max_seconds_naming_it():
    import time

    calls = []

    def slow(s):
        calls.append(1)
        time.sleep(0.2)
        return np.maximum(s.depth_mm, 0)

    start = time.perf_counter()
    raised(slow, r"^solver\.max_seconds = 0\.5 s reached in the growth rule python:.*slow: its last call took 0\.2\d\d s, \d+ calls \d+\.\d{3} s in all$",
           kind=eyeshell.SolverError, solver__max_seconds=0.5)
    # Stopped at the first call past the limit: not retried by the integrator.
    assert time.perf_counter() - start < 2.0 and len(calls) <= 5, len(calls)


def test_ctrl_c_stops_a_rule_that_never_returns():
    seconds, out, err, code = interrupt(f"""
        import time, eyeshell
        def stuck(s):
            print("started", flush=True)
            while True:
                time.sleep(0.01)
        try:
            eyeshell.grow({CONST!r}, stimulus=stuck, solver__nodes=51, frames=False)
            print("finished")
        except KeyboardInterrupt:
            print("interrupted")
    """)
    assert code == 0 and out.strip() == "interrupted", (out, err)
    assert seconds < 2.0


def test_a_failing_rule_is_not_called_again():
    # The integrators take a failed evaluation as recoverable and retry with smaller
    # steps; a Python rule that failed is not called again.
    calls = []

    def once(s):
        calls.append(s.t)
        if len(calls) > 3:
            raise RuntimeError("tired")
        return np.maximum(s.depth_mm, 0)

    raised(once, r"raised RuntimeError: tired$")
    assert len(calls) == 4
