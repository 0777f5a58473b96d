"""Tests of thermaxis.method.selection (temperature-sensitive point selection).

Expected numbers come from published worked examples (cited per test) or are
worked out by hand in the comments; none is output of the code captured once.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from thermaxis.method.grey import absolute_grey_incidence, grey_relational_grade
from thermaxis.method.selection import (
    SensitivePoints,
    classes_for_count,
    common_points,
    fuzzy_equivalence,
    lambda_cut_classes,
    max_min_compose,
    rank_by_correlation,
    select_sensitive_points,
    similarity_matrix,
)

# The paper's choices (Pearson similarity, Deng's grade, rho 0.5 on min-max sequences),
# spelled out: the library takes them from config ``selection``, never from defaults.
DENG = {"rho": 0.5, "normalisation": "minmax"}
PAPER = {"similarity": "pearson", "grade": "deng", **DENG}

# --------------------------------------------------------------------------- #
# published worked examples: fuzzy equivalence clustering
# --------------------------------------------------------------------------- #
# Sivanandam S.N., Sumathi S., Deepa S.N., "Introduction to Fuzzy Logic using
# MATLAB", Springer 2007, section 3.5.3, Example 3.8 (reproduced at
# https://123dok.com/id/article/fuzzy-relation-tolerance-and-equivalence-relations.11313469):
# the tolerance relation R, its first composition R o R and the equivalence
# relation reached "after one or two more compositions".
SIVANANDAM_R = np.array(
    [
        [1.0, 0.6, 0.0, 0.2, 0.3],
        [0.6, 1.0, 0.4, 0.0, 0.8],
        [0.0, 0.4, 1.0, 0.0, 0.0],
        [0.2, 0.0, 0.0, 1.0, 0.5],
        [0.3, 0.8, 0.0, 0.5, 1.0],
    ]
)
SIVANANDAM_R2 = np.array(
    [
        [1.0, 0.6, 0.4, 0.3, 0.6],
        [0.6, 1.0, 0.4, 0.5, 0.8],
        [0.4, 0.4, 1.0, 0.0, 0.4],
        [0.3, 0.5, 0.0, 1.0, 0.5],
        [0.6, 0.8, 0.4, 0.5, 1.0],
    ]
)
SIVANANDAM_CLOSURE = np.array(
    [
        [1.0, 0.6, 0.4, 0.5, 0.6],
        [0.6, 1.0, 0.4, 0.5, 0.8],
        [0.4, 0.4, 1.0, 0.4, 0.4],
        [0.5, 0.5, 0.4, 1.0, 0.5],
        [0.6, 0.8, 0.4, 0.5, 1.0],
    ]
)

# Classic textbook example of fuzzy clustering of five objects (Chinese fuzzy
# mathematics courses, e.g. the lecture "模糊聚类分析",
# max.book118.com/html/2016/0807/50629140.shtm,
# which prints the maximum tree x1-x3 (0.8), x4-x5 (0.6), then edges of 0.5
# and 0.4, and the partitions lambda = 0.8: {x1,x3},{x2},{x4},{x5} and
# lambda = 0.6: {x1,x3},{x2},{x4,x5}).
TEXTBOOK_R = np.array(
    [
        [1.0, 0.1, 0.8, 0.5, 0.3],
        [0.1, 1.0, 0.1, 0.2, 0.4],
        [0.8, 0.1, 1.0, 0.3, 0.1],
        [0.5, 0.2, 0.3, 1.0, 0.6],
        [0.3, 0.4, 0.1, 0.6, 1.0],
    ]
)
# Closure by hand: for max-min, t(R)[i, j] is the strongest "weakest link" of a
# path i -> j, read off the maximum tree: x1-x3 0.8; x4-x5 0.6; x1/x3 to x4/x5
# via the 0.5 edge x1-x4; x2 joins only through x2-x5 = 0.4.
TEXTBOOK_CLOSURE = np.array(
    [
        [1.0, 0.4, 0.8, 0.5, 0.5],
        [0.4, 1.0, 0.4, 0.4, 0.4],
        [0.8, 0.4, 1.0, 0.5, 0.5],
        [0.5, 0.4, 0.5, 1.0, 0.6],
        [0.5, 0.4, 0.5, 0.6, 1.0],
    ]
)


def test_max_min_compose_reproduces_sivanandam_first_composition():
    np.testing.assert_array_equal(max_min_compose(SIVANANDAM_R, SIVANANDAM_R), SIVANANDAM_R2)


def test_closure_reproduces_sivanandam_example_3_8():
    np.testing.assert_array_equal(fuzzy_equivalence(SIVANANDAM_R), SIVANANDAM_CLOSURE)


def test_lambda_cuts_of_sivanandam_closure():
    # Partitions read off the published closure by hand (0-based indices).
    expected = {
        1.0: [(0,), (1,), (2,), (3,), (4,)],
        0.8: [(0,), (1, 4), (2,), (3,)],  # x2-x5
        0.6: [(0, 1, 4), (2,), (3,)],  # + x1
        0.5: [(0, 1, 3, 4), (2,)],  # + x4
        0.4: [(0, 1, 2, 3, 4)],  # + x3
    }
    for eta, classes in expected.items():
        assert lambda_cut_classes(SIVANANDAM_CLOSURE, eta) == classes


def test_closure_and_partitions_of_textbook_example():
    closure = fuzzy_equivalence(TEXTBOOK_R)
    np.testing.assert_array_equal(closure, TEXTBOOK_CLOSURE)
    # The two partitions printed in the source, plus the coarser levels.
    assert lambda_cut_classes(closure, 0.8) == [(0, 2), (1,), (3,), (4,)]
    assert lambda_cut_classes(closure, 0.6) == [(0, 2), (1,), (3, 4)]
    assert lambda_cut_classes(closure, 0.5) == [(0, 2, 3, 4), (1,)]
    assert lambda_cut_classes(closure, 0.4) == [(0, 1, 2, 3, 4)]


def test_classes_for_count_on_textbook_example():
    closure = fuzzy_equivalence(TEXTBOOK_R)
    assert classes_for_count(closure, 3) == ([(0, 2), (1,), (3, 4)], 0.6)
    assert classes_for_count(closure, 2) == ([(0, 2, 3, 4), (1,)], 0.5)
    assert classes_for_count(closure, 5) == ([(0,), (1,), (2,), (3,), (4,)], 1.0)
    assert classes_for_count(closure, 1) == ([(0, 1, 2, 3, 4)], 0.4)


def test_closure_equals_the_papers_squaring_on_a_tied_matrix():
    # Eq. 2 as the paper computes it: R, R o R, ... until a square repeats.
    rng = np.random.default_rng(11)
    A = np.round(rng.random((25, 25)), 1)
    R = np.maximum(A, A.T)
    np.fill_diagonal(R, 1.0)
    squared = R
    while not np.array_equal(max_min_compose(squared, squared), squared):
        squared = max_min_compose(squared, squared)
    np.testing.assert_array_equal(fuzzy_equivalence(R), squared)


def test_classes_for_count_equals_scipy_components_at_every_level_of_a_tied_matrix():
    # An unsymmetric matrix on 40 sensors, mostly weak links, with many ties (entries in
    # steps of 0.05, so some counts are skipped where several links join at once): for
    # each distinct entry, from the largest down, scipy's connected components of the cut
    # (linked where either direction reaches eta); the first entry giving each count is
    # what classes_for_count must return for it.
    from scipy.sparse.csgraph import connected_components

    rng = np.random.default_rng(7)
    E = np.round(rng.random((40, 40)) ** 12 * 20) / 20
    expected = {}
    for eta in np.unique(E)[::-1]:
        count, labels = connected_components((E >= eta) | (E.T >= eta), directed=False)
        members = {}
        for sensor, label in enumerate(labels):
            members.setdefault(label, []).append(sensor)
        classes = sorted(tuple(m) for m in members.values())
        expected.setdefault(count, (classes, float(eta)))
    assert len(expected) > 5
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for count, answer in expected.items():
            assert classes_for_count(E, count) == answer


def test_lambda_cut_eta_between_levels_gives_same_partition_as_next_level_up():
    # Any eta in (0.5, 0.6] cuts exactly like 0.6.
    assert lambda_cut_classes(TEXTBOOK_CLOSURE, 0.55) == lambda_cut_classes(TEXTBOOK_CLOSURE, 0.6)


# --------------------------------------------------------------------------- #
# classes_for_count when ties make the count impossible
# --------------------------------------------------------------------------- #
def test_classes_for_count_tie_prefers_finer_partition_and_warns():
    # Two pairs merge at the same level 0.5, so the counts jump 4 -> 2 -> 1.
    E = np.array(
        [
            [1.0, 0.5, 0.2, 0.2],
            [0.5, 1.0, 0.2, 0.2],
            [0.2, 0.2, 1.0, 0.5],
            [0.2, 0.2, 0.5, 1.0],
        ]
    )
    with pytest.warns(UserWarning, match=r"no lambda-cut gives 3 classes.*using 4 classes"):
        classes, eta = classes_for_count(E, 3)
    assert classes == [(0,), (1,), (2,), (3,)]
    assert eta == 1.0


def test_classes_for_count_takes_nearest_count_when_not_tied():
    E = np.full((4, 4), 0.3)
    np.fill_diagonal(E, 1.0)  # achievable counts: 4 (eta 1) and 1 (eta 0.3)
    with pytest.warns(UserWarning, match=r"2 classes.*using 1 class instead"):
        classes, eta = classes_for_count(E, 2)
    assert classes == [(0, 1, 2, 3)]
    assert eta == 0.3


def test_classes_for_count_rejects_impossible_request():
    with pytest.raises(ValueError, match="n_classes"):
        classes_for_count(TEXTBOOK_CLOSURE, 6)
    with pytest.raises(ValueError, match="n_classes"):
        classes_for_count(TEXTBOOK_CLOSURE, 0)


# --------------------------------------------------------------------------- #
# similarity matrix
# --------------------------------------------------------------------------- #
def test_similarity_pearson_and_printed_by_hand():
    # a = (0,0,2,2): deviations (-1,-1,1,1); e = (2,0,0,2): deviations (1,-1,-1,1);
    # b = 2a + 1 (same shape); c = (2,2,0,0) = mirror of a.
    X = np.array([[0, 2, 1, 2], [0, 0, 1, 2], [2, 0, 5, 0], [2, 2, 5, 0]], dtype=float)
    # Pearson: r(a,e) = (-1+1-1+1)/(2*2) = 0; r(a,b) = 1; r(a,c) = -1 -> |r| = 1.
    expected_pearson = np.array(
        [
            [1, 0, 1, 1],
            [0, 1, 0, 0],
            [1, 0, 1, 1],
            [1, 0, 1, 1],
        ],
        dtype=float,
    )
    np.testing.assert_allclose(similarity_matrix(X, "pearson"), expected_pearson, atol=1e-12)
    # Printed Eq. 1: sum |da||de| / (2*2) = 4/4 = 1 although a and e are uncorrelated.
    np.testing.assert_allclose(similarity_matrix(X, method="printed"), np.ones((4, 4)), atol=1e-12)


def test_similarity_pearson_matches_numpy_corrcoef_and_accepts_dataframe():
    rng = np.random.default_rng(20240501)
    X = rng.normal(size=(8, 5)).cumsum(axis=0)
    expected = np.abs(np.corrcoef(X, rowvar=False))
    np.testing.assert_allclose(similarity_matrix(X, "pearson"), expected, atol=1e-12)
    frame = pd.DataFrame(X, columns=[f"T{i}" for i in range(1, 6)])
    np.testing.assert_allclose(similarity_matrix(frame, "pearson"), expected, atol=1e-12)


def test_similarity_printed_is_never_below_pearson():
    rng = np.random.default_rng(7)
    X = rng.normal(size=(8, 6))
    assert np.all(similarity_matrix(X, "printed") >= similarity_matrix(X, "pearson") - 1e-12)


def test_similarity_constant_column_warns_and_is_isolated():
    X = np.array([[1.0, 20.0, 3.0], [2.0, 20.0, 1.0], [3.0, 20.0, 2.0]])
    with pytest.warns(UserWarning, match=r"constant sensor column\(s\) \[1\]"):
        R = similarity_matrix(X, "pearson")
    assert R[1, 1] == 1.0
    assert R[1, 0] == R[0, 1] == R[1, 2] == R[2, 1] == 0.0
    # r(col0, col2): deviations (-1,0,1) and (1,-1,0) -> -1/2.
    assert R[0, 2] == pytest.approx(0.5)


@pytest.mark.parametrize(
    "X, method, match",
    [
        (np.ones((3, 2)), "spearman", "similarity method"),
        (np.ones(3), "pearson", "2-D"),
        (np.ones((1, 3)), "pearson", "at least 2 samples"),
        (np.array([[1.0, np.nan], [2.0, 3.0]]), "pearson", "NaN"),
    ],
)
def test_similarity_rejects_bad_input(X, method, match):
    with pytest.raises(ValueError, match=match):
        similarity_matrix(X, method=method)


# --------------------------------------------------------------------------- #
# fuzzy equivalence: input checks
# --------------------------------------------------------------------------- #
def test_fuzzy_equivalence_rejects_non_similarity_matrices():
    with pytest.raises(ValueError, match="symmetric"):
        fuzzy_equivalence([[1.0, 0.2], [0.3, 1.0]])
    with pytest.raises(ValueError, match="reflexive"):
        fuzzy_equivalence([[0.9, 0.2], [0.2, 1.0]])
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        fuzzy_equivalence([[1.0, 1.5], [1.5, 1.0]])
    with pytest.raises(ValueError, match="square"):
        fuzzy_equivalence(np.ones((2, 3)))


def test_lambda_cut_rejects_eta_outside_unit_interval():
    with pytest.raises(ValueError, match="eta"):
        lambda_cut_classes(TEXTBOOK_CLOSURE, 1.2)


# --------------------------------------------------------------------------- #
# property tests: closure and nesting
# --------------------------------------------------------------------------- #
LEVELS = [round(0.1 * i, 1) for i in range(11)]


@st.composite
def similarity_matrices(draw):
    n = draw(st.integers(min_value=1, max_value=7))
    upper = draw(
        st.lists(st.sampled_from(LEVELS), min_size=n * (n - 1) // 2, max_size=n * (n - 1) // 2)
    )
    R = np.eye(n)
    R[np.triu_indices(n, k=1)] = upper
    return np.maximum(R, R.T)


def widest_path_closure(R):
    """Independent method: Floyd-Warshall on the bottleneck (max of min) path strength."""
    P = R.copy()
    for k in range(P.shape[0]):
        P = np.maximum(P, np.minimum(P[:, [k]], P[[k], :]))
    return P


@settings(max_examples=150, deadline=None)
@given(similarity_matrices())
def test_closure_is_reflexive_symmetric_transitive_idempotent(R):
    E = fuzzy_equivalence(R)
    np.testing.assert_array_equal(np.diag(E), 1.0)
    np.testing.assert_array_equal(E, E.T)
    assert np.all(max_min_compose(E, E) <= E)  # max-min transitive
    np.testing.assert_array_equal(fuzzy_equivalence(E), E)  # idempotent
    assert np.all(E >= R)  # contains R
    np.testing.assert_array_equal(E, widest_path_closure(R))  # and is the smallest such


@settings(max_examples=150, deadline=None)
@given(similarity_matrices())
def test_classes_nest_as_lambda_falls(R):
    E = fuzzy_equivalence(R)
    n = E.shape[0]
    previous = None
    for eta in sorted(set(LEVELS) | set(np.unique(E).tolist()), reverse=True):
        classes = lambda_cut_classes(E, eta)
        assert sorted(i for c in classes for i in c) == list(range(n))  # a partition
        if previous is not None:
            # every finer class (higher eta) lies inside one coarser class
            for fine in previous:
                assert sum(set(fine) <= set(coarse) for coarse in classes) == 1
            assert len(classes) <= len(previous)
        previous = classes


@settings(max_examples=100, deadline=None)
@given(similarity_matrices(), st.integers(min_value=1, max_value=7))
def test_classes_for_count_is_consistent_with_the_cut(R, requested):
    E = fuzzy_equivalence(R)
    requested = min(requested, E.shape[0])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        classes, eta = classes_for_count(E, requested)
    assert classes == lambda_cut_classes(E, eta)
    assert eta in set(np.unique(E).tolist())
    assert (len(classes) == requested) == (len(caught) == 0)


# --------------------------------------------------------------------------- #
# Deng's grey relational grade
# --------------------------------------------------------------------------- #
def test_deng_grade_minmax_by_hand_uses_global_two_level_extremes():
    # x0 = (0,1,2) -> (0, .5, 1); x1 = (0,2,2) -> (0, 1, 1); x2 = (2,1,0) -> (1, .5, 0).
    # D1 = (0, .5, 0), D2 = (1, 0, 1); over BOTH sensors min = 0, max = 1.
    # xi = (0 + .5*1)/(D + .5*1): x1 -> (1, .5, 1) mean 5/6; x2 -> (1/3, 1, 1/3) mean 5/9.
    # (Per-sensor extremes would give x1 (1, 1/3, 1) -> 7/9 instead.)
    X = np.array([[0.0, 2.0], [2.0, 1.0], [2.0, 0.0]])
    np.testing.assert_allclose(
        grey_relational_grade([0, 1, 2], X, **DENG), [5 / 6, 5 / 9], rtol=1e-12
    )
    # rho = 1: xi = 1/(D + 1): x1 -> (1, 2/3, 1) -> 8/9; x2 -> (1/2, 1, 1/2) -> 2/3.
    np.testing.assert_allclose(
        grey_relational_grade([0, 1, 2], X, rho=1.0, normalisation="minmax"),
        [8 / 9, 2 / 3],
        rtol=1e-12,
    )


def test_deng_grade_initial_and_mean_normalisation_by_hand():
    # initial: x0 (2,4,6) -> (1,2,3); x1 (1,2,4) -> (1,2,4); x2 (4,4,4) -> (1,1,1).
    # D1 = (0,0,1), D2 = (0,1,2); min 0, max 2, rho*max = 1.
    # x1: (1, 1, 1/2) -> 5/6; x2: (1, 1/2, 1/3) -> 11/18.
    X = np.array([[1.0, 4.0], [2.0, 4.0], [4.0, 4.0]])
    np.testing.assert_allclose(
        grey_relational_grade([2, 4, 6], X, rho=0.5, normalisation="initial"),
        [5 / 6, 11 / 18],
        rtol=1e-12,
    )
    # mean: x0 (1,2,3) -> (.5,1,1.5); x1 (2,2,2) -> (1,1,1); x2 (3,6,9) -> (.5,1,1.5).
    # D1 = (.5,0,.5), D2 = 0; min 0, max .5, rho*max = .25.
    # x1: (1/3, 1, 1/3) -> 5/9; x2: 1.
    X = np.array([[2.0, 3.0], [2.0, 6.0], [2.0, 9.0]])
    np.testing.assert_allclose(
        grey_relational_grade([1, 2, 3], X, rho=0.5, normalisation="mean"), [5 / 9, 1.0], rtol=1e-12
    )


# Worked example "which industry drives GDP" (regional GDP 2000-2005, million
# yuan) from the Chinese mathematical-modelling tutorial on grey relational
# analysis, e.g. https://m.douchai.cn/document/379879252.html ("灰色模型") and
# https://e-com-net.com/article/1355185540634324992.htm.  Published: the raw
# data and the mean-normalised table below (4 decimals).
GDP_RAW = np.array(
    [
        # GDP, primary, secondary, tertiary industry
        [1988, 386, 839, 763],
        [2061, 408, 846, 808],
        [2335, 422, 960, 953],
        [2750, 482, 1258, 1010],
        [3356, 511, 1577, 1268],
        [3806, 561, 1893, 1352],
    ],
    dtype=float,
)
GDP_MEAN_NORMALISED_PUBLISHED = np.array(
    [
        [0.7320, 0.8361, 0.6828, 0.7439],
        [0.7588, 0.8838, 0.6885, 0.7878],
        [0.8597, 0.9141, 0.7812, 0.9292],
        [1.0125, 1.0440, 1.0237, 0.9847],
        [1.2356, 1.1069, 1.2833, 1.2363],
        [1.4013, 1.2152, 1.5405, 1.3182],
    ]
)


def test_deng_grade_reproduces_gdp_worked_example():
    """Deng's grade, mean normalisation, rho = 0.5, on the published GDP example.

    From the published normalised table, |x0 - xi| (rows 2000..2005):
      primary   .1041 .1250 .0544 .0315 .1287 .1861
      secondary .0492 .0703 .0785 .0112 .0477 .1392
      tertiary  .0119 .0290 .0695 .0278 .0007 .0831
    two-level min = .0007 (2004, tertiary), max = .1861 (2005, primary);
    xi = (.0007 + .5*.1861) / (D + .5*.1861), averaged over the six years:
      primary   (.4755+.4299+.6358+.7527+.4228+.3358)/6 = .5088
      secondary (.6591+.5739+.5465+.8993+.6661+.4037)/6 = .6247
      tertiary  (.8933+.7681+.5767+.7758+1.000+.5322)/6 = .7577
    The 4-decimal rounding of the table moves the grades by < 1e-3.
    """
    x0, X = GDP_RAW[:, 0], GDP_RAW[:, 1:]
    # Our mean normalisation reproduces the published table ...
    np.testing.assert_allclose(
        GDP_RAW / GDP_RAW.mean(axis=0), GDP_MEAN_NORMALISED_PUBLISHED, atol=5e-5
    )
    # ... and the grades match the hand arithmetic above.
    grades = grey_relational_grade(x0, X, rho=0.5, normalisation="mean")
    np.testing.assert_allclose(grades, [0.5088, 0.6247, 0.7577], atol=1e-3)
    assert list(np.argsort(grades)) == [0, 1, 2]  # tertiary > secondary > primary


def test_deng_grade_initial_normalisation_rejects_zero_first_value():
    # Relative temperatures (as used for the intercept b) start at 0.
    relative = np.array([[0.0, 0.0], [0.4, 0.1], [0.9, 0.3]])
    with pytest.raises(ValueError, match="initial-value normalisation.*non-zero first value"):
        grey_relational_grade([1.0, 2.0, 3.0], relative, rho=0.5, normalisation="initial")


def test_deng_grade_minmax_constant_sensor_warns_and_scores_as_zeros():
    # x0 = (0,1,2) -> (0,.5,1); constant x1 -> (0,0,0); x2 = x0.  D1 = (0,.5,1), D2 = 0.
    # min 0, max 1: x1 -> (1, .5, 1/3) -> 11/18; x2 -> 1.
    X = np.array([[5.0, 0.0], [5.0, 1.0], [5.0, 2.0]])
    with pytest.warns(UserWarning, match=r"constant sequence\(s\) \[1\]"):
        grades = grey_relational_grade([0, 1, 2], X, **DENG)
    np.testing.assert_allclose(grades, [11 / 18, 1.0], rtol=1e-12)


def test_deng_grade_identical_sequences_give_one():
    X = np.column_stack([np.arange(4.0), 2 * np.arange(4.0) + 1])
    np.testing.assert_array_equal(grey_relational_grade(np.arange(4.0), X, **DENG), [1.0, 1.0])


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"rho": 0.0}, "rho"),
        ({"rho": 1.5}, "rho"),
        ({"normalisation": "zscore"}, "normalisation"),
    ],
)
def test_deng_grade_rejects_bad_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        grey_relational_grade(
            [1.0, 2.0, 3.0], np.ones((3, 2)) + np.arange(3)[:, None], **{**DENG, **kwargs}
        )


def test_deng_grade_rejects_length_mismatch():
    with pytest.raises(ValueError, match="x0 must be a 1-D sequence of 3 samples"):
        grey_relational_grade([1.0, 2.0], np.ones((3, 2)), **DENG)


# --------------------------------------------------------------------------- #
# absolute degree of grey incidence
# --------------------------------------------------------------------------- #
def test_absolute_grey_incidence_by_hand():
    # X0 = (10,9,15,14,14,15): zero-started (0,-1,5,4,4,5);
    #   s0 = -1+5+4+4 + 5/2 = 14.5
    # X1 = (46,58,70,77,84,91): zero-started (0,12,24,31,38,45);
    #   s1 = 12+24+31+38 + 45/2 = 127.5;  s1 - s0 = 113
    # eps = (1+14.5+127.5)/(1+14.5+127.5+113) = 143/256
    x0 = [10, 9, 15, 14, 14, 15]
    X1 = np.array([46, 58, 70, 77, 84, 91], dtype=float)
    # X2 = X0 + 100 has the same zero-started image -> eps = 1.
    # X3 = 2*X0: s3 = 29, |s3 - s0| = 14.5 -> eps = (1+14.5+29)/(1+14.5+29+14.5) = 44.5/59.
    X = np.column_stack([X1, np.add(x0, 100), np.multiply(x0, 2)])
    np.testing.assert_allclose(
        absolute_grey_incidence(x0, X), [143 / 256, 1.0, 44.5 / 59], rtol=1e-12
    )


# --------------------------------------------------------------------------- #
# select_sensitive_points
# --------------------------------------------------------------------------- #
def _three_group_readings():
    """Eight measurements of five sensors in three groups built so the answer is known.

    Group A: T1 = k, T2 = k plus a small wiggle (|r(T1,T2)| ~ 0.9996).
    Group B: T3 = (k - 3.5)^2 and T4 = 2*T3 + 1 (identical shape, r = 1).
    Group C: T5 = (-1)^k.  Across groups |r| <= 0.3 (e.g. r(k, (k-3.5)^2) = 0 by symmetry).
    """
    k = np.arange(8.0)
    wiggle = np.array([0.0, 0.1, 0.0, -0.1, 0.0, 0.1, 0.0, -0.1])
    quad = (k - 3.5) ** 2
    return pd.DataFrame(
        {"T1": k, "T2": k + wiggle, "T3": quad, "T4": 2 * quad + 1, "T5": (-1.0) ** k}
    )


def test_select_sensitive_points_on_constructed_groups():
    X = _three_group_readings()
    y = 3.0 * X["T2"] + 5.0  # the target has exactly T2's shape
    result = select_sensitive_points(X, y, n_clusters=3, **PAPER)
    assert isinstance(result, SensitivePoints)
    assert result.clusters == (("T1", "T2"), ("T3", "T4"), ("T5",))
    # T2 matches y after min-max scaling -> every coefficient 1 -> grade 1.
    assert result.grades["T2"] == pytest.approx(1.0, abs=1e-12)
    # T3 and T4 have the same min-max image -> equal grades -> the earlier, T3.
    assert result.grades["T3"] == result.grades["T4"]
    assert result.selected == ("T2", "T3", "T5")
    assert list(result.grades) == ["T1", "T2", "T3", "T4", "T5"]
    # Group A joins at its own |r| (computed here by numpy, a different route).
    assert result.eta == pytest.approx(abs(np.corrcoef(X["T1"], X["T2"])[0, 1]), abs=1e-12)


def test_select_sensitive_points_with_absolute_degree():
    X = _three_group_readings()
    y = X["T2"].to_numpy() + 100.0  # same zero-started image as T2 -> degree 1
    result = select_sensitive_points(X, y, **{**PAPER, "grade": "absolute"}, n_clusters=3)
    assert result.grades["T2"] == pytest.approx(1.0, abs=1e-12)
    assert result.selected[0] == "T2"
    assert result.clusters == (("T1", "T2"), ("T3", "T4"), ("T5",))


def test_select_sensitive_points_selected_follows_column_order():
    X = _three_group_readings()[["T5", "T3", "T4", "T1", "T2"]]
    y = 3.0 * X["T2"] + 5.0
    result = select_sensitive_points(X, y, n_clusters=3, **PAPER)
    assert result.clusters == (("T5",), ("T3", "T4"), ("T1", "T2"))
    assert result.selected == ("T5", "T3", "T2")


def test_select_sensitive_points_rejects_bad_input():
    X = _three_group_readings()
    with pytest.raises(ValueError, match="grade"):
        select_sensitive_points(X, X["T1"], n_clusters=3, **{**PAPER, "grade": "pearson"})
    with pytest.raises(ValueError, match="y must be a 1-D sequence of 8 samples"):
        select_sensitive_points(X, X["T1"].to_numpy()[:5], n_clusters=3, **PAPER)
    with pytest.raises(ValueError, match="DataFrame"):
        select_sensitive_points(X.to_numpy(), X["T1"], n_clusters=3, **PAPER)
    with pytest.raises(ValueError, match="initial-value"):
        select_sensitive_points(
            X, X["T1"] + 1.0, n_clusters=3, **{**PAPER, "normalisation": "initial"}
        )  # T1 starts at 0


# --------------------------------------------------------------------------- #
# baseline rules
# --------------------------------------------------------------------------- #
def test_rank_by_correlation_by_hand():
    # y = k = 0..4.  T1 = k (|r| = 1), T2 = -k (|r| = 1), T3 = k^2:
    # deviations (-2,-1,0,1,2) and (-6,-5,-2,3,10) -> r = 40/sqrt(10*174) = 0.959;
    # T4 = (1,-1,1,-1,1): sum of k-deviation * T4-deviation = 0 -> r = 0.
    k = np.arange(5.0)
    X = pd.DataFrame({"T4": [1.0, -1, 1, -1, 1], "T3": k**2, "T2": -k, "T1": k})
    # T2 and T1 tie at |r| = 1: column order puts T2 first.
    assert rank_by_correlation(X, k, 3) == ("T2", "T1", "T3")
    assert rank_by_correlation(X, k, 4) == ("T2", "T1", "T3", "T4")
    with pytest.raises(ValueError, match="n must be an integer"):
        rank_by_correlation(X, k, 5)
    with pytest.raises(ValueError, match="y is constant"):
        rank_by_correlation(X, np.ones(5), 2)
    with pytest.warns(UserWarning, match=r"constant sensor\(s\) \['T0'\]"):
        ranked = rank_by_correlation(X.assign(T0=7.0), k, 5)
    assert ranked == ("T2", "T1", "T3", "T4", "T0")  # T4 and T0 both |r| = 0: column order


# Xu et al. (the reproduced paper), Table 3: sensitive points found per
# position by point-by-point selection; the paper keeps the three chosen most
# often, T1, T11, T12 (counts 10, 9, 8; next T7 with 7).
PAPER_TABLE_3 = [
    ["T2", "T7", "T11"],  # 185 mm
    ["T2", "T7", "T11"],  # 205
    ["T1", "T7", "T11"],  # 225
    ["T4", "T7", "T12"],  # 245
    ["T4", "T7", "T11"],  # 265
    ["T1", "T11", "T12"],  # 285
    ["T1", "T11", "T12"],  # 305
    ["T1", "T6", "T12"],  # 325
    ["T1", "T6", "T12"],  # 345
    ["T1", "T6", "T12"],  # 365
    ["T1", "T7", "T11"],  # 385
    ["T1", "T11", "T12"],  # 405
    ["T1", "T6", "T7"],  # 425
    ["T1", "T11", "T12"],  # 445
]
SENSOR_ORDER = [f"T{i}" for i in range(1, 13)]


def test_common_points_reproduces_paper_table_3():
    assert common_points(PAPER_TABLE_3, 3, order=SENSOR_ORDER) == ("T1", "T11", "T12")
    assert common_points(PAPER_TABLE_3, 4, order=SENSOR_ORDER) == ("T1", "T11", "T12", "T7")


def test_common_points_tie_break_and_duplicates():
    selections = [["T2", "T1", "T2"], ["T1", "T2"]]  # the repeated T2 counts once
    assert common_points(selections, 1, order=SENSOR_ORDER) == ("T1",)
    assert common_points(selections, 1, order=SENSOR_ORDER[::-1]) == ("T2",)
    assert common_points(selections, 1) == ("T2",)  # default: first appearance
    with pytest.raises(ValueError, match="order lacks"):
        common_points(selections, 1, order=["T1"])
    with pytest.raises(ValueError, match="n must be an integer"):
        common_points(selections, 3)
