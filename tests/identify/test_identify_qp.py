"""The QP on the Gram matrix (pihyst.identify._qp) against scipy, its constraints and warnings;
the plain metric functions."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import lsq_linear, nnls

from pihyst.exceptions import IllConditionedWarning, InfeasibleConstraintsError
from pihyst.identify._qp import solve_qp
from pihyst.metrics import error_summary, max_abs_error, mean_abs_error, rms_error


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 12), extra=st.integers(0, 60))
def test_qp_equals_nnls_on_the_full_matrix(seed, n, extra):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n + extra + 1, n)) * rng.uniform(0.1, 10, size=n)
    d = rng.normal(size=A.shape[0]) * 5
    x_ref, _ = nnls(A, d)
    sol = solve_qp(A.T @ A, A.T @ d, lower=0.0, warn=False)
    if sol.regularized:
        return
    assert np.all(sol.x >= 0)
    # same minimum of ||A x - d|| (the minimizer is unique when A has full rank)
    r_qp, r_ref = np.linalg.norm(A @ sol.x - d), np.linalg.norm(A @ x_ref - d)
    assert r_qp <= r_ref * (1 + 1e-9) + 1e-12
    np.testing.assert_allclose(sol.x, x_ref, rtol=1e-6, atol=1e-8 * np.abs(x_ref).max(initial=1))


def test_qp_with_operator_matrix_of_a_pi_model_matches_nnls():
    from pihyst import ClassicalPI
    u = np.r_[np.linspace(0, 150, 301), np.linspace(150, 20, 261), np.linspace(20, 110, 181)]
    phi = ClassicalPI(np.arange(8) * 9.0, np.ones(8)).operators(u)
    d = 0.2 * u + 3 * np.sin(u / 20)
    x_ref, _ = nnls(phi, d)
    sol = solve_qp(phi.T @ phi, phi.T @ d, lower=0.0)
    np.testing.assert_allclose(sol.x, x_ref, rtol=1e-7, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_bounds_match_scipy_lsq_linear(seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(40, 5))
    d = rng.normal(size=40)
    lo = rng.uniform(-1, 0, 5)
    hi = lo + rng.uniform(0.01, 1, 5)
    ref = lsq_linear(A, d, bounds=(lo, hi), method="bvls", tol=1e-12).x
    sol = solve_qp(A.T @ A, A.T @ d, lower=lo, upper=hi)
    assert np.all(sol.x >= lo) and np.all(sol.x <= hi)
    np.testing.assert_allclose(sol.x, ref, atol=1e-7)


def test_equality_constraints_are_met_exactly_and_optimal():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(50, 4))
    d = rng.normal(size=50)
    E = np.array([[1.0, 1.0, 1.0, 1.0]])
    sol = solve_qp(A.T @ A, A.T @ d, A_eq=E, b_eq=[2.0])
    assert abs(sol.x.sum() - 2.0) < 1e-12
    # KKT of the equality-constrained LS: [H E^T; E 0][x; l] = [g; b]
    H, g = A.T @ A, A.T @ d
    K = np.block([[H, E.T], [E, np.zeros((1, 1))]])
    ref = np.linalg.solve(K, np.r_[g, 2.0])[:4]
    np.testing.assert_allclose(sol.x, ref, atol=1e-10)


def test_dependent_but_consistent_equalities_are_accepted():
    rng = np.random.default_rng(4)
    A = rng.normal(size=(30, 3))
    d = rng.normal(size=30)
    E = np.array([[1.0, 0, 0], [2.0, 0, 0]])
    sol = solve_qp(A.T @ A, A.T @ d, A_eq=E, b_eq=[0.5, 1.0], lower=0)
    assert sol.x[0] == pytest.approx(0.5)


@pytest.mark.parametrize("kwargs", [
    {"lower": [0, 0, 1], "upper": [1, 1, 0.5]},
    {"A_eq": [[1, 0, 0], [1, 0, 0]], "b_eq": [1, 2]},
    {"lower": 0.0, "A_eq": [[1, 1, 1]], "b_eq": [-1]},
])
def test_infeasible_constraints_raise(kwargs):
    A = np.eye(3)
    with pytest.raises(InfeasibleConstraintsError):
        solve_qp(A, np.ones(3), **kwargs)


def test_ill_conditioned_gives_best_admissible_solution_and_warns():
    rng = np.random.default_rng(5)
    a = rng.normal(size=(100, 2))
    A = np.c_[a, a[:, 0]]                  # column 2 duplicates column 0
    d = a @ [1.0, 2.0] + 0.01 * rng.normal(size=100)
    with pytest.warns(IllConditionedWarning, match="x\\[0\\], x\\[2\\]"):
        sol = solve_qp(A.T @ A, A.T @ d, lower=0.0)
    assert sol.regularized and sol.condition > 1e11
    # the fit is as good as the best well-posed one, and the duplicates share the weight
    x_ref, _ = nnls(a, d)
    assert np.linalg.norm(A @ sol.x - d) <= np.linalg.norm(a @ x_ref - d) * (1 + 1e-6)
    assert sol.x[0] == pytest.approx(sol.x[2], rel=1e-4)
    assert sol.x[0] + sol.x[2] == pytest.approx(x_ref[0], rel=1e-6)


def test_no_warning_when_asked_not_to():
    A = np.c_[np.ones(10), np.ones(10)]
    sol = solve_qp(A.T @ A, A.T @ np.ones(10), warn=False)
    assert sol.regularized
    assert np.allclose(A @ sol.x, 1.0, atol=1e-6)


def test_inputs_not_modified():
    rng = np.random.default_rng(6)
    A = rng.normal(size=(20, 3))
    H, g = A.T @ A, A.T @ rng.normal(size=20)
    H0, g0 = H.copy(), g.copy()
    solve_qp(H, g, lower=0.0, A_eq=[[1, 1, 1]], b_eq=[1])
    assert np.array_equal(H, H0) and np.array_equal(g, g0)


def test_bad_shapes_raise():
    with pytest.raises(ValueError):
        solve_qp(np.eye(2), np.ones(3))
    with pytest.raises(ValueError):
        solve_qp(np.eye(2), [np.nan, 1.0])


def test_metrics():
    y = np.array([0.0, 1.0, 2.0, 3.0])
    p = np.array([0.0, 2.0, 2.0, 1.0])
    assert mean_abs_error(y, p) == pytest.approx(0.75)
    assert max_abs_error(y, p) == pytest.approx(2.0)
    assert rms_error(y, p) == pytest.approx(np.sqrt(5 / 4))
    s = error_summary(y, p, measured_range=3.0)
    assert s["max_abs_pct"] == pytest.approx(200 / 3)
    with pytest.raises(ValueError):
        rms_error([1, 2], [1])
    with pytest.raises(ValueError):
        rms_error([], [])
