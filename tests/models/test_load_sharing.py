"""Load sharing among tooth pairs: seed 003 Eqs. 5-8 against a direct solve, and the active set.

Sources: the compatibility conditions of seed 003 (Eqs. 5a-c, 9, 12, 15: equal transmission
error for every loaded pair, loads summing to F) and its rule that a pair with non-positive load
leaves contact (Eqs. 11, 14, 17); SEED-NOTES 14 (rebuild the garbled closed forms and test them
against a linear solve).
"""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from models.errors import ModelError
from models.stiffness.load_sharing import (
    load_sharing_closed_form,
    load_sharing_two_pairs,
    solve_load_sharing,
)

# compliances of real tooth pairs: 2e-9 .. 2e-8 m/N; errors of a few um; loads up to 10 kN
compliances = st.floats(1e-9, 2e-8)
errors = st.floats(-20e-6, 20e-6)
loads = st.floats(0.0, 1e4)


def direct_solve(c, e, f):
    """The compatibility system [diag(C) -1; 1 0] [F; x] = [-e; F] by numpy.linalg.solve."""
    n = len(c)
    a = np.zeros((n + 1, n + 1))
    b = np.zeros(n + 1)
    a[np.arange(n), np.arange(n)] = c
    a[:n, n] = -1.0
    b[:n] = -np.asarray(e)
    a[n, :n] = 1.0
    b[n] = f
    sol = np.linalg.solve(a, b)
    return sol[:n], sol[n]


def brute_force_active_set(c, g, f):
    """The unique solution by enumerating every subset of pairs (the complementarity problem)."""
    c, g = np.asarray(c), np.asarray(g)
    n = len(c)
    for size in range(1, n + 1):
        for sub in itertools.combinations(range(n), size):
            if not all(np.isfinite(g[list(sub)])):
                continue
            fs, x = direct_solve(c[list(sub)], g[list(sub)], f)
            if np.all(fs > 0):
                out = np.zeros(n)
                out[list(sub)] = fs
                others = [i for i in range(n) if i not in sub]
                if all(g[i] >= x - 1e-15 for i in others):
                    return out, x
    raise AssertionError("no consistent active set")


@settings(max_examples=200, deadline=None)
@given(compliances, compliances, errors, errors, st.floats(1.0, 1e4))
def test_eq6_two_pairs_equals_direct_solve(c1, c2, e1, e2, f):
    # seed 003 Eq. 6a-c against the linear solve of Eq. 5a-c
    r = load_sharing_two_pairs(c1, c2, e1, e2, f)
    fs, x = direct_solve([c1, c2], [e1, e2], f)
    np.testing.assert_allclose(r.loads_N, fs, rtol=1e-9, atol=1e-6,
                               err_msg="seed 003 Eq. 6b-c vs direct solve")
    np.testing.assert_allclose(r.transmission_error_m, x, rtol=1e-9, atol=1e-15,
                               err_msg="seed 003 Eq. 6a vs direct solve")
    # Eq. 7: LSR_1 = (C2 + e21 / F) / (C1 + C2)
    np.testing.assert_allclose(r.load_sharing_ratio[0], (c2 + (e2 - e1) / f) / (c1 + c2),
                               rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("n", [2, 3])
@settings(max_examples=100, deadline=None)
@given(data=st.data())
def test_eq8_n_pairs_equals_direct_solve(n, data):
    # seed 003 Eq. 8a-c for n = 2 and 3 (normal and high contact ratio)
    c = data.draw(st.lists(compliances, min_size=n, max_size=n))
    e = data.draw(st.lists(errors, min_size=n, max_size=n))
    f = data.draw(st.floats(1.0, 1e4))
    r = load_sharing_closed_form(c, e, f)
    fs, x = direct_solve(c, e, f)
    np.testing.assert_allclose(r.loads_N, fs, rtol=1e-9, atol=1e-6, err_msg="Eq. 8b")
    np.testing.assert_allclose(r.transmission_error_m, x, rtol=1e-9, atol=1e-15,
                               err_msg="Eq. 8a")
    # loads sum to F (up to the cancellation of error-driven loads of opposite sign)
    assert r.loads_N.sum() == pytest.approx(f, rel=1e-12, abs=1e-12 * np.abs(fs).max())


@settings(max_examples=100, deadline=None)
@given(n=st.integers(1, 8), seed=st.integers(0, 2**32 - 1))
def test_eq8_any_n_vectorised_equals_direct_solve(n, seed):
    rng = np.random.default_rng(seed)
    c = rng.uniform(1e-9, 2e-8, (7, n))
    e = rng.uniform(-20e-6, 20e-6, (7, n))
    f = rng.uniform(1.0, 1e4, 7)
    r = load_sharing_closed_form(c, e, f)
    for j in range(7):
        fs, x = direct_solve(c[j], e[j], f[j])
        np.testing.assert_allclose(r.loads_N[j], fs, rtol=1e-9, atol=1e-6)
        np.testing.assert_allclose(r.transmission_error_m[j], x, rtol=1e-9, atol=1e-15)


@settings(max_examples=100, deadline=None)
@given(compliances, compliances, errors, errors, loads)
def test_eq6_is_eq8_for_two_pairs(c1, c2, e1, e2, f):
    a = load_sharing_two_pairs(c1, c2, e1, e2, f)
    b = load_sharing_closed_form([c1, c2], [e1, e2], f)
    np.testing.assert_allclose(a.loads_N, b.loads_N, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(a.transmission_error_m, b.transmission_error_m, rtol=1e-9,
                               atol=1e-16)


@settings(max_examples=300, deadline=None)
@given(n=st.integers(1, 5), seed=st.integers(0, 2**32 - 1), f=st.floats(1.0, 1e4))
def test_active_set_is_the_unique_complementarity_solution(n, seed, f):
    # seed 003 Eqs. 9-17: non-positive loads leave contact; checked against subset enumeration
    rng = np.random.default_rng(seed)
    c = rng.uniform(1e-9, 2e-8, n)
    g = rng.uniform(-10e-6, 40e-6, n)
    g[rng.random(n) < 0.2] = np.inf  # some pairs cannot touch
    if not np.isfinite(g).any():
        g[0] = 0.0
    r = solve_load_sharing(c, g, f)
    ref, x = brute_force_active_set(c, g, f)
    np.testing.assert_allclose(r.loads_N, ref, rtol=1e-9, atol=1e-6)
    assert float(r.transmission_error_m) == pytest.approx(x, rel=1e-9, abs=1e-15)
    # loads sum to F; LSR in [0, 1]; loaded pairs satisfy x = C F + g, the others stay open
    assert r.loads_N.sum() == pytest.approx(f, rel=1e-12)
    assert np.all((r.load_sharing_ratio >= 0) & (r.load_sharing_ratio <= 1))
    on = r.in_contact
    np.testing.assert_allclose(c[on] * r.loads_N[on] + g[on], x, rtol=1e-9, atol=1e-15)
    assert np.all(g[~on] >= x - 1e-15)


def test_active_set_vectorised_over_positions_matches_per_position():
    rng = np.random.default_rng(3)
    c = rng.uniform(1e-9, 1e-8, (50, 4))
    g = rng.uniform(0, 30e-6, (50, 4))
    f = rng.uniform(100, 5000, 50)
    r = solve_load_sharing(c, g, f)
    for j in range(50):
        one = solve_load_sharing(c[j], g[j], f[j])
        np.testing.assert_allclose(r.loads_N[j], one.loads_N, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(r.loads_N.sum(axis=1), f, rtol=1e-12)


def test_hand_checkable_limits():
    # equal pairs, no errors: equal shares, x = C F / n
    r = solve_load_sharing([2e-9] * 3, [0.0] * 3, 3000.0)
    np.testing.assert_allclose(r.loads_N, 1000.0)
    assert float(r.transmission_error_m) == pytest.approx(2e-9 * 1000.0)
    # an error larger than C1 F: pair 2 never touches (seed Eq. 11)
    r = solve_load_sharing([2e-9, 2e-9], [0.0, 2e-9 * 3000.0 + 1e-7], 3000.0)
    np.testing.assert_allclose(r.loads_N, [3000.0, 0.0])
    assert r.in_contact.tolist() == [True, False]
    # stiffer pair carries more: shares in proportion to stiffness without errors (Eq. 7)
    r = solve_load_sharing([1e-9, 3e-9], [0.0, 0.0], 4000.0)
    np.testing.assert_allclose(r.load_sharing_ratio, [0.75, 0.25])


def test_zero_load_is_the_limit_of_small_load():
    c, g = np.array([1e-9, 3e-9, 2e-9]), np.array([0.0, 0.0, 5e-6])
    r0 = solve_load_sharing(c, g, 0.0)
    r1 = solve_load_sharing(c, g, 1e-3)
    assert float(r0.transmission_error_m) == 0.0
    assert r0.in_contact.tolist() == [True, True, False]
    np.testing.assert_allclose(r0.load_sharing_ratio, r1.load_sharing_ratio, rtol=1e-9)
    np.testing.assert_allclose(r0.loads_N, 0.0)


def test_invalid_inputs_are_refused_with_the_argument_named():
    with pytest.raises(ModelError, match="`compliance` must be finite and > 0"):
        solve_load_sharing([1e-9, -1e-9], [0, 0], 1.0)
    with pytest.raises(ModelError, match="`load_N` must be finite and >= 0"):
        solve_load_sharing([1e-9, 1e-9], [0, 0], -1.0)
    with pytest.raises(ModelError, match="`gap` must be finite for at least one pair"):
        solve_load_sharing([1e-9, 1e-9], [np.inf, np.inf], 1.0)
    with pytest.raises(ModelError, match="`gap` must be finite or"):
        solve_load_sharing([1e-9, 1e-9], [np.nan, 0], 1.0)
    with pytest.raises(ModelError, match="last axis over the tooth pairs"):
        load_sharing_closed_form(1e-9, 0.0, 1.0)
