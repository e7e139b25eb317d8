"""The discrete equations in the user's hands (issue 49): eyeshell.residual and
eyeshell.jacobian on the non-uniform fibre shell, checked as a user would check them, and
the states they refuse."""

import numpy as np
import pytest

import eyeshell
from conftest import SCENES, optional


def fibre_scene(nodes: int) -> eyeshell.Scene:
    return eyeshell.Scene.from_file(SCENES / "fibres-nonuniform.toml").set("solver.nodes", nodes)


def test_a_solved_state_satisfies_the_equations_to_newton_tol():
    scene = fibre_scene(201)
    sol = eyeshell.solve(scene)
    state = sol.state
    assert state.shape == (5 * len(sol),)
    # The layout: (κ, r, θ, q_s, t_s) by node.
    nodes = state.reshape(-1, 5)
    assert np.array_equal(nodes[:, 0], sol.kappa) and np.array_equal(nodes[:, 1], sol.r)
    assert np.array_equal(nodes[:, 4], sol.t_s)
    assert np.allclose(nodes[:, 1] * nodes[:, 3], sol.Q, rtol=1e-14, atol=1e-14)
    scaled = eyeshell.residual(scene, state, scaled=True)
    assert scaled.shape == state.shape
    assert np.abs(scaled).max() <= scene["solver.newton_tol"], np.abs(scaled).max()
    # Unscaled, the r rows are R0 = 10 times larger: not below newton_tol by construction.
    raw = eyeshell.residual(scene, state)
    assert np.abs(raw).max() < 1e-9
    # Away from the solution the residual is not small.
    moved = state.copy()
    moved[1::5] *= 1 + 1e-6
    assert np.abs(eyeshell.residual(scene, moved, scaled=True)).max() > 1e-7


def test_the_jacobian_is_the_central_differences_of_the_residual():
    optional("scipy")
    scene = fibre_scene(101)
    state = eyeshell.solve(scene).state
    # Off the solution, so that every term of the Jacobian counts.
    state = state * (1 + 1e-3 * np.sin(np.arange(state.size)))
    J = eyeshell.jacobian(scene, state)
    assert J.shape == (state.size, state.size)
    dense = J.toarray()
    # Steps relative to κ, r, t_s (never near zero; r is 1e-3 at the pole) and at least
    # 1e-6 of a typical size for θ and q_s, which vanish there.
    floor = np.tile([0.0, 0.0, 1.0, 10.0, 0.0], state.size // 5)
    worst = 0.0
    for j in range(state.size):
        h = 1e-6 * max(abs(state[j]), floor[j])
        up, down = state.copy(), state.copy()
        up[j] += h
        down[j] -= h
        fd = (eyeshell.residual(scene, up) - eyeshell.residual(scene, down)) / (2 * h)
        scale = np.abs(dense[:, j]).max()
        assert scale > 0, f"column {j} is zero"
        worst = max(worst, np.abs(fd - dense[:, j]).max() / scale)
    assert worst <= 1e-6, worst


def test_bad_states_are_refused_in_one_line():
    scene = fibre_scene(41)
    state = eyeshell.solve(scene).state
    n = state.size
    for bad, needle in [
        (state[:-1], f"the state has {n - 1} values; the scene's mesh has {n // 5} nodes × 5 unknowns"),
        (np.concatenate([state, state]), f"the state has {2 * n} values"),
        (state.reshape(-1, 5), "state must be a 1-D array"),
    ]:
        for f in (eyeshell.residual, eyeshell.jacobian):
            with pytest.raises(eyeshell.InputError) as e:
                f(scene, bad)
            assert needle in str(e.value) and "\n" not in str(e.value), str(e.value)
            assert len(str(e.value)) <= 300
    nan = state.copy()
    nan[7] = np.nan
    with pytest.raises(eyeshell.InputError, match=r"value 7 \(θ at node 1\) is nan"):
        eyeshell.residual(scene, nan)
    inward = state.copy()
    inward[5 * 10 + 1] = -1.0  # r < 0 at node 10
    with pytest.raises(eyeshell.InputError, match="node 10"):
        eyeshell.residual(scene, inward)
    with pytest.raises(eyeshell.InputError, match="solver.tol"):
        eyeshell.residual(scene.set("solver.tol", 1e-6), state)
