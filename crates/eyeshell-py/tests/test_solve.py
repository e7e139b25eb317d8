"""eyeshell.solve against the exact sphere, against the command line bit for bit, and its
bvp4c export read back by `eyeshell compare`."""

import json

import numpy as np
import pytest

import eyeshell
from conftest import SCENES, optional, read_csv


def test_the_exact_sphere_to_1e_10():
    """docs/MODEL.md §7: uniform inflation by the cornea's stretch α."""
    sol = eyeshell.solve(SCENES / "exact-sphere.toml", solver__nodes=1601)
    alpha, r0, h0, c = sol.summary["cornea_alpha"], 10.0, 0.65, 100.0
    S = sol.Sigma
    exact = {
        "r": alpha * r0 * np.sin(S / r0),
        "theta": S / r0,
        "kappa": np.full_like(S, 1 / (alpha * r0)),
        "alpha_s": np.full_like(S, alpha),
        "alpha_phi": np.full_like(S, alpha),
        "Q": np.zeros_like(S),
        "t_s": np.full_like(S, 2 * h0 * c * (1 - alpha**-6)),
    }
    for name, want in exact.items():
        error = np.abs(sol.fields[name] - want).max()
        assert error < 1e-10, f"{name}: max error {error:.3e}"
    # The interpolant between the nodes is as good.
    mid = 0.5 * (S[1:] + S[:-1])
    assert np.abs(sol.at(mid)["r"] - alpha * r0 * np.sin(mid / r0)).max() < 1e-10


@pytest.mark.parametrize("scene", ["fibres-nonuniform.toml", "default.toml"])
def test_fields_are_the_command_lines_bit_for_bit(cli, tmp_path, scene):
    at = [0.5, 7.853981633974483, 12.0]
    cli("solve", SCENES / scene, "--set", "solver.nodes=301", "--at", ",".join(map(repr, at)),
        "--out", tmp_path / "run", "--quiet")
    sol = eyeshell.solve(SCENES / scene, **{"solver.nodes": 301})
    fields = read_csv(tmp_path / "run" / "fields.csv")
    assert list(fields) == list(sol.fields)
    for name, values in fields.items():
        assert np.array_equal(np.array(values), sol.fields[name]), name
    for name, values in read_csv(tmp_path / "run" / "at.csv").items():
        assert np.array_equal(np.array(values), sol.at(at)[name]), name
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    for k in ["newton_iterations", "residual_norm", "first_integral_max", "nodes", "parameters",
              "components", "sundials_version", "scheme"]:
        assert sol.summary[k] == summary[k], k


def test_arrays_are_handed_over_not_copied():
    sol = eyeshell.solve(solver__nodes=101)
    # NumPy owns no copy: the buffer is the Rust Vec's, kept alive by its container.
    for a in [sol.r, sol.Sigma, sol.y, sol.yp]:
        assert not a.flags.owndata and type(a.base).__name__ == "PySliceContainer"
    assert sol.r is sol.fields["r"]
    # No interface on the uniform shell without fibres: bvp4c's x is the nodes.
    assert np.array_equal(sol.x, sol.Sigma)
    assert sol.y.flags.f_contiguous  # MATLAB's order, as the export built it


def test_yp_is_f_of_y():
    sol = eyeshell.solve(SCENES / "fibres-nonuniform.toml", solver__nodes=201)
    # bvp4c's yp is f(x, y): r′ = α_s cos θ and θ′ = α_s κ (docs/MODEL.md §3) at every
    # point of x, the interfaces' two copies each from its own side (a difference of the
    # node values is off by about 1e-7 at this N).
    kappa, alpha_s, r, theta, q = sol.y
    assert np.abs(sol.yp[2] - alpha_s * np.cos(theta)).max() <= 1e-13
    assert np.abs(sol.yp[3] - alpha_s * kappa).max() <= 1e-13
    repeated = sol.x[1:][np.diff(sol.x) == 0]
    assert np.allclose(repeated, np.pi * 10 / 2 * np.array([1 / 20, 1 / 4, 1]), rtol=1e-15)
    assert len(sol.x) == len(sol) + 3


def test_to_bvp4c_saved_by_scipy_is_read_back_by_eyeshell_compare(cli, tmp_path):
    scipy_io = optional("scipy.io")
    sol = eyeshell.solve(SCENES / "fibres-nonuniform.toml", solver__nodes=401)
    sol4c = sol.to_bvp4c()
    # Σ_e and the fibre kinks a, b are in x twice (bvp4c's interfaces).
    assert sol4c["solver"] == "bvp4c" and sol4c["y"].shape == (5, len(sol) + 3)
    assert sol4c["stats"]["nmeshpoints"] == len(sol.x)
    scipy_io.savemat(tmp_path / "sol.mat", {"sol": sol4c})
    back = scipy_io.loadmat(tmp_path / "sol.mat", squeeze_me=True)["sol"]
    assert np.array_equal(back["y"].item(), sol.y)
    # The command line's run of the same scene meets it to round-off ...
    cli("solve", SCENES / "fibres-nonuniform.toml", "--set", "solver.nodes=401", "--out",
        tmp_path / "run", "--quiet")
    r = cli("compare", tmp_path / "run", tmp_path / "sol.mat", "--tol", "1e-13", "--rtol", "0")
    assert "sol" in r.stdout
    c = eyeshell.compare(tmp_path / "run", tmp_path / "sol.mat", tol=1e-13, rtol=0)
    assert c.passed and c.pairs[0]["points"] == len(sol.x)
    assert set(c.pairs[0]["fields"]) >= {"kappa", "r", "theta"}
    # ... and a perturbed copy fails, by the amount put in.
    sol4c["y"] = sol4c["y"].copy()
    sol4c["y"][2, 100] += 1e-6
    scipy_io.savemat(tmp_path / "bad.mat", {"sol": sol4c})
    bad = eyeshell.compare(tmp_path / "run", tmp_path / "bad.mat", tol=1e-9, rtol=0)
    assert not bad.passed and bad.pairs[0]["fields"]["r"]["failures"] == 1
    assert abs(bad.pairs[0]["fields"]["r"]["max_abs"] - 1e-6) < 1e-12
    assert cli("compare", tmp_path / "run", tmp_path / "bad.mat", "--tol", "1e-9", "--rtol", "0",
               check=False).returncode == 1


def test_solutions_pickle_and_solve_again_when_asked():
    import pickle

    sol = eyeshell.solve(solver__nodes=101, fibres__D=100)
    back = pickle.loads(pickle.dumps(sol))
    assert np.array_equal(back.r, sol.r) and back.summary == sol.summary
    assert back.at(3.0) == sol.at(3.0)


def test_solve_reports_a_growth_runs_first_refraction(cli, tmp_path):
    """Solution.refraction_D is a growth run's first refraction_D (the same loaded, ungrown
    retina and optics) to 1e-6 D, and summary.json's and the command line's; through the
    Solution's eye too. A scene that neither grows nor computes its optics has none."""
    scene = SCENES / "eyewear" / "single-vision.toml"
    sets = {"solver.nodes": 101}
    sol = eyeshell.solve(scene, **sets)
    barely = {"growth.t_end": 1e-6, "output.times": [1e-6], "output.history_points": 0}
    g = eyeshell.grow(scene, frames=False, **sets, **barely)
    first = float(g.series["refraction_D"][0])
    assert abs(sol.refraction_D - first) < 1e-6
    assert abs(first - 10.4623) < 1e-3
    assert sol.eye["refraction_D"] == sol.refraction_D
    assert sol.summary["refraction_D"] == sol.refraction_D
    cli("solve", scene, "--set", "solver.nodes=101", "--out", tmp_path / "run", "--quiet")
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["refraction_D"] == sol.refraction_D
    # The shell alone: no eye to refract through, said by None and no key.
    bare = eyeshell.solve(SCENES / "default.toml", **sets)
    assert bare.refraction_D is None
    assert "refraction_D" not in bare.summary and "refraction_D" not in bare.eye
    # A scene that does not grow refracts through its own optics when it computes them: the
    # four-surface eye (24 mm long) before the 19.96 mm shell is strongly hyperopic.
    own = eyeshell.solve(SCENES / "four-surfaces.toml", **sets, **{"stimulus.source": "optics"})
    assert 5.0 < own.refraction_D < 25.0
