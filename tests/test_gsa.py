"""experiments/pumasim_exp/gsa.py against closed forms: the Ishigami function's Sobol indices
(Sobol' and Levitan 1999), Morris's elementary effects of a linear function (each exactly its
coefficient), and the Saltelli design's structure.

    /usr/bin/python3 -m pytest -q tests/test_gsa.py
"""
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "experiments"))
from pumasim_exp import gsa  # noqa: E402


def test_saltelli_design_swaps_one_column_each():
    a, b, ab = gsa.saltelli(3, 64, seed=1)
    assert a.shape == b.shape == (64, 3) and ab.shape == (3, 64, 3)
    for i in range(3):
        expect = a.copy()
        expect[:, i] = b[:, i]
        assert np.array_equal(ab[i], expect)
    assert np.all((a >= 0) & (a < 1)) and np.all((b >= 0) & (b < 1))
    with pytest.raises(gsa.GsaError, match="power of 2"):
        gsa.saltelli(3, 100, seed=1)


def test_sobol_indices_of_ishigami_match_the_closed_form():
    """S1 = (0.3139, 0.4424, 0) and ST = (0.5576, 0.4424, 0.2437) for a = 7, b = 0.1. Each estimate
    within twice its 95 % bootstrap half-width (about four standard errors) of the closed form."""
    s1_exact, st_exact = gsa.ishigami_exact()
    assert s1_exact == pytest.approx([0.3139, 0.4424, 0.0], abs=1e-4)
    assert st_exact == pytest.approx([0.5576, 0.4424, 0.2437], abs=1e-4)
    a, b, ab = gsa.saltelli(3, 2 ** 14, seed=3)
    x = lambda u: -math.pi + 2 * math.pi * u  # noqa: E731
    r = gsa.sobol_indices(gsa.ishigami(x(a)), gsa.ishigami(x(b)), gsa.ishigami(x(ab)), bootstrap=300, seed=4)
    for name, exact in (("S1", s1_exact), ("ST", st_exact)):
        err = np.abs(r[name] - exact)
        assert np.all(err <= 2 * r[name + "_conf"] + 1e-3), (name, r[name], exact, r[name + "_conf"])
        assert np.all(r[name + "_conf"] < 0.05), r[name + "_conf"]


def test_morris_effects_of_a_linear_function_are_its_coefficients():
    c = np.array([3.0, -1.5, 0.0, 0.25])
    traj, moves, signs = gsa.morris_trajectories(4, r=20, levels=4, seed=5)
    assert traj.shape == (20, 5, 4) and np.all((traj >= 0) & (traj <= 1 + 1e-15))
    # each step moves one factor by +-Delta = 4 / (2 * 3)
    steps = np.abs(np.diff(traj, axis=1))
    assert np.allclose(np.sort(steps, axis=2)[..., -1], 2 / 3) and np.allclose(np.sort(steps, axis=2)[..., :-1], 0)
    f = traj @ c
    m = gsa.morris_indices(f, moves, signs, bootstrap=100, seed=6)
    assert m["mu"] == pytest.approx(c, abs=1e-12)
    assert m["mu_star"] == pytest.approx(np.abs(c), abs=1e-12)
    assert m["sigma"] == pytest.approx(np.zeros(4), abs=1e-12)


def test_to_factors_maps_the_unit_cube_onto_the_distributions():
    factors = [{"key": "a.u", "distribution": "uniform", "low": 2.0, "high": 4.0},
               {"key": "a.l", "distribution": "log-uniform", "low": 1e-3, "high": 1e-1},
               {"key": "a.n", "distribution": "normal", "mean": 1.0, "sd": 0.5}]
    v = gsa.to_factors(np.array([[0.0, 0.0, 0.5], [0.5, 0.5, 0.975]]), factors)
    assert v[0] == pytest.approx([2.0, 1e-3, 1.0])
    assert v[1] == pytest.approx([3.0, 1e-2, 1.0 + 0.5 * 1.959963984540054])
    with pytest.raises(gsa.GsaError, match="choice"):
        gsa.to_factors(np.zeros((1, 1)), [{"key": "a.c", "distribution": "choice", "values": [1, 2]}])


def test_a_failed_run_turns_the_outputs_into_the_failure_indicator():
    # experiments/ensemble_gsa.py: a failed run has no outputs; with one, the only column indexed is
    # `failed` (1 for a failed run), and with none, each output as read.
    import ensemble_gsa
    ok = {"sample": "0", "ok": "1", "max_path_error": "0.5", "failure": ""}
    bad = {"sample": "1", "ok": "0", "max_path_error": "", "failure": "unstable at t = 1 s"}
    n, cols = ensemble_gsa.output_columns([ok, bad, ok], ["max_path_error"])
    assert n == 1 and [c for c, _ in cols] == ["failed"]
    np.testing.assert_array_equal(cols[0][1], [0.0, 1.0, 0.0])
    n, cols = ensemble_gsa.output_columns([ok, ok], ["max_path_error"])
    assert n == 0 and cols[0][0] == "max_path_error"
    np.testing.assert_array_equal(cols[0][1], [0.5, 0.5])
    assert ensemble_gsa.first_failure([ok, bad]) == "sample 1: unstable at t = 1 s"
