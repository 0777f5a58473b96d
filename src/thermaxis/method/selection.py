"""Temperature-sensitive point selection: fuzzy clustering + grey relational analysis.

The paper (section 1, steps 1-4) picks the *sensitive points* among the
temperature sensors in four steps:

1. a fuzzy similarity matrix between sensors (Eq. 1) -> :func:`similarity_matrix`;
2. its max-min transitive closure, the fuzzy equivalence matrix (Eq. 2)
   -> :func:`fuzzy_equivalence`;
3. a lambda-cut (Eq. 3) whose threshold eta gives the requested number of
   classes -> :func:`lambda_cut_classes`, :func:`classes_for_count`;
4. in each class, the sensor with the largest grey relational grade to the
   target sequence (Deng's grade, Eq. 4; the text also names Liu Sifeng's
   absolute degree) -> :func:`~thermaxis.method.grey.grey_relational_grade`,
   :func:`~thermaxis.method.grey.absolute_grey_incidence`.

:func:`select_sensitive_points` chains the four steps on a table of sensor
readings.  :func:`rank_by_correlation` and :func:`common_points` are the two
simpler rules the study compares against (the top-|r| baseline and the
paper's Table 3 rule "the points chosen most often across positions").

All numeric functions are pure (arrays in, arrays out); only the last three
functions deal with sensor names.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from thermaxis.errors import DataError, SelectionWarning
from thermaxis.method.grey import (
    absolute_grey_incidence,
    as_samples_by_sensors,
    as_sequence,
    grey_relational_grade,
)

__all__ = [
    "SensitivePoints",
    "informative_sensors",
    "similarity_matrix",
    "fuzzy_equivalence",
    "max_min_compose",
    "lambda_cut_classes",
    "classes_for_count",
    "select_sensitive_points",
    "rank_by_correlation",
    "common_points",
]

SIMILARITY_METHODS = ("pearson", "printed")
GRADES = ("deng", "absolute")

# Entries of a fuzzy relation are compared exactly elsewhere (max-min only ever
# copies entries), but symmetry/reflexivity of an input computed in floating
# point (e.g. |Pearson r|) needs a tolerance.
_ATOL = 1e-12


# --------------------------------------------------------------------------- #
# input checks
# --------------------------------------------------------------------------- #
def _as_fuzzy_relation(R, name: str) -> np.ndarray:
    arr = np.asarray(R, dtype=float)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or arr.shape[0] < 1:
        raise ValueError(f"{name} must be a square matrix, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)) or arr.min() < -_ATOL or arr.max() > 1 + _ATOL:
        raise ValueError(f"{name} entries must lie in [0, 1]")
    return np.clip(arr, 0.0, 1.0)


def _sensor_names(X: pd.DataFrame) -> list[str]:
    if not isinstance(X, pd.DataFrame):
        raise ValueError("X must be a pandas DataFrame whose columns are the sensor ids")
    names = [str(c) for c in X.columns]
    if len(set(names)) != len(names):
        raise ValueError(f"sensor ids (columns of X) must be unique, got {names}")
    return names


# --------------------------------------------------------------------------- #
# step 1: fuzzy similarity matrix (Eq. 1)
# --------------------------------------------------------------------------- #
def _unit_deviations(arr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Columns minus their mean, scaled to unit length; constant columns become zeros."""
    dev = arr - arr.mean(axis=0)
    norms = np.sqrt(np.sum(dev**2, axis=0))
    # Relative to the column's own magnitude so that round-off in the mean of
    # a constant column does not count as variation.
    scale = np.maximum(np.abs(arr).max(axis=0), 1.0)
    constant = norms <= 1e-12 * scale * np.sqrt(arr.shape[0])
    unit = np.where(constant, 0.0, dev / np.where(constant, 1.0, norms))
    return unit, constant


def similarity_matrix(X, method: str) -> np.ndarray:
    """Fuzzy similarity matrix between sensors (the paper's Eq. 1).

    Parameters
    ----------
    X : array-like or DataFrame, shape (n_samples, n_sensors)
        One column per sensor, one row per sample (measurement).
    method : {"pearson", "printed"}
        ``"pearson"`` (default): ``r_ij = |Pearson r|`` of sensors i and j.
        ``"printed"``: Eq. 1 exactly as printed, with absolute values on each
        factor of the numerator,
        ``sum_k |dx_i(k)| |dx_j(k)| / (sqrt(sum_k dx_i(k)^2) sqrt(sum_k dx_j(k)^2))``
        with ``dx = x - mean(x)``; the printed second root uses ``x_i`` with
        ``mean(x_j)``, a typo fixed here to ``x_j``.  By Cauchy-Schwarz it lies
        in [0, 1] and is never below ``|r|``.

    Returns
    -------
    numpy.ndarray, shape (n_sensors, n_sensors)
        Symmetric, entries in [0, 1], ones on the diagonal.

    Notes
    -----
    A constant sensor has no defined correlation; it gets similarity 0 with
    every other sensor and 1 with itself, so it ends up in a class of its own,
    and a :class:`UserWarning` names its column index.
    """
    if method not in SIMILARITY_METHODS:
        raise ValueError(f"similarity method must be one of {SIMILARITY_METHODS}, got {method!r}")
    unit, constant = _unit_deviations(as_samples_by_sensors(X))
    if constant.any():
        warnings.warn(
            f"constant sensor column(s) {np.flatnonzero(constant).tolist()}: "
            "similarity set to 0 with every other sensor",
            SelectionWarning,
            stacklevel=2,
        )
    if method == "pearson":
        sim = np.abs(unit.T @ unit)
    else:
        sim = np.abs(unit).T @ np.abs(unit)
    sim = np.clip((sim + sim.T) / 2.0, 0.0, 1.0)
    np.fill_diagonal(sim, 1.0)
    return sim


# --------------------------------------------------------------------------- #
# step 2: fuzzy equivalence matrix (Eq. 2)
# --------------------------------------------------------------------------- #
def max_min_compose(A, B) -> np.ndarray:
    """Max-min composition ``(A o B)[i, j] = max_k min(A[i, k], B[k, j])``.

    Parameters
    ----------
    A, B : array-like, shapes (n, m) and (m, p)

    Returns
    -------
    numpy.ndarray, shape (n, p)
    """
    a = np.asarray(A, dtype=float)
    b = np.asarray(B, dtype=float)
    if a.ndim != 2 or b.ndim != 2 or a.shape[1] != b.shape[0]:
        raise ValueError(f"cannot max-min compose shapes {a.shape} and {b.shape}")
    return np.minimum(a[:, :, None], b[None, :, :]).max(axis=1)


def fuzzy_equivalence(R) -> np.ndarray:
    """Fuzzy equivalence matrix t(R): the max-min transitive closure of R (Eq. 2).

    The paper reaches it by squaring, ``R -> R o R -> (R o R) o (R o R) -> ...`` until a
    square equals its predecessor (:func:`max_min_compose`). For a reflexive symmetric
    relation that fixed point is, for each pair, the strongest chain of links between
    them: the largest, over chains, of the weakest link on the chain. A maximum spanning
    tree of R holds a strongest chain for every pair, so the closure is built here while
    the tree grows (Prim), in O(n^2): a sensor joining through a link of strength w to
    tree sensor p reaches every tree sensor k at min(w, t(R)[p, k]). The squarings took
    O(n^3 log n) time and an n^3 temporary (0.9 s and 216 MB a call on 300 sensors).
    Entries are entries of R either way (min and max only select), so the two agree
    exactly (tests/unit/test_selection.py).

    Parameters
    ----------
    R : array-like, shape (n, n)
        Fuzzy similarity matrix: entries in [0, 1], symmetric, ones on the
        diagonal (as returned by :func:`similarity_matrix`).

    Returns
    -------
    numpy.ndarray, shape (n, n)
        Reflexive, symmetric, max-min transitive and idempotent under max-min
        composition.  Its entries are a subset of the entries of R (max-min
        only selects values), so exact comparisons on it are meaningful.
    """
    rel = _as_fuzzy_relation(R, "R")
    if not np.allclose(rel, rel.T, rtol=0.0, atol=1e-9):
        raise ValueError("R must be symmetric (a fuzzy similarity matrix)")
    if not np.allclose(np.diag(rel), 1.0, rtol=0.0, atol=1e-9):
        raise ValueError("R must be reflexive: every diagonal entry must be 1")
    rel = (rel + rel.T) / 2.0
    np.fill_diagonal(rel, 1.0)
    n = rel.shape[0]
    closure = np.eye(n)
    in_tree = np.zeros(n, dtype=bool)
    in_tree[0] = True
    tree = [0]
    # For each sensor outside the tree: its strongest link into the tree, and to whom.
    link, parent = rel[0].copy(), np.zeros(n, dtype=int)
    for _ in range(n - 1):
        joining = int(np.argmax(np.where(in_tree, -1.0, link)))
        reach = np.minimum(link[joining], closure[parent[joining], tree])
        closure[joining, tree] = reach
        closure[tree, joining] = reach
        in_tree[joining] = True
        tree.append(joining)
        stronger = rel[joining] > link
        link[stronger], parent[stronger] = rel[joining, stronger], joining
    return closure


# --------------------------------------------------------------------------- #
# step 3: lambda-cut classes (Eq. 3)
# --------------------------------------------------------------------------- #
def lambda_cut_classes(E, eta: float) -> list[tuple[int, ...]]:
    """Classes of the lambda-cut ``E >= eta`` (Eq. 3).

    Entries ``>= eta`` become 1, the rest 0; sensors linked by 1 form a class.
    On a fuzzy equivalence matrix the cut is already an equivalence relation;
    on any other matrix the classes are the connected components of the cut
    (its transitive closure), so the result is always a partition.

    Parameters
    ----------
    E : array-like, shape (n, n)
        Fuzzy equivalence matrix (:func:`fuzzy_equivalence`).
    eta : float
        Threshold in [0, 1].

    Returns
    -------
    list of tuple of int
        Canonical order: each class sorted ascending, classes sorted by their
        first (smallest) member.
    """
    rel = _as_fuzzy_relation(E, "E")
    if not (0.0 <= float(eta) <= 1.0):
        raise ValueError(f"eta must lie in [0, 1], got {eta}")
    linked = (rel >= eta) | (rel.T >= eta)
    n = rel.shape[0]
    label = np.full(n, -1)
    classes: list[tuple[int, ...]] = []
    for start in range(n):
        if label[start] >= 0:
            continue
        members, frontier = {start}, [start]
        label[start] = len(classes)
        while frontier:
            node = frontier.pop()
            for nxt in np.flatnonzero(linked[node]):
                if label[nxt] < 0:
                    label[nxt] = len(classes)
                    members.add(int(nxt))
                    frontier.append(int(nxt))
        classes.append(tuple(sorted(members)))
    # Scanning starts in ascending order, so classes already come sorted by
    # their first member.
    return classes


def _cuts_by_count(rel: np.ndarray) -> dict[int, tuple[list[tuple[int, ...]], float]]:
    """Every partition the lambda-cuts of ``rel`` give, by its number of classes, each
    with the largest eta that gives it (an entry of ``rel``).

    The cuts nest: sensors i and j are linked from eta = max(r_ij, r_ji) down, so as eta
    falls through the distinct link strengths classes only merge (single linkage). One
    pass of union-find over the links, strongest first, therefore yields every cut. A
    :func:`lambda_cut_classes` search at each distinct entry took 0.07 s a call on 100
    sensors, 16 s of a 100-sensor record's statistics job.
    """
    n = rel.shape[0]
    parent = list(range(n))

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    def partition() -> list[tuple[int, ...]]:
        # Members in ascending order, classes by their first member: lambda_cut_classes' order.
        classes: dict[int, list[int]] = {}
        for k in range(n):
            classes.setdefault(root(k), []).append(k)
        return [tuple(members) for members in classes.values()]

    first, second = np.triu_indices(n, k=1)
    strength = np.maximum(rel, rel.T)[first, second]
    top = float(rel.max())
    by_count: dict[int, tuple[list[tuple[int, ...]], float]] = {}
    if not strength.size or strength.max() < top:
        by_count[n] = ([(k,) for k in range(n)], top)
    order = np.argsort(-strength, kind="stable")
    # Links of equal strength join at one eta: the bounds of each run of them in ``order``.
    bounds = [*np.unique(-strength[order], return_index=True)[1], order.size]
    count = n
    for start, stop in zip(bounds[:-1], bounds[1:], strict=True):
        for link in order[start:stop]:
            a, b = root(int(first[link])), root(int(second[link]))
            if a != b:
                parent[max(a, b)] = min(a, b)
                count -= 1
        by_count.setdefault(count, (partition(), float(strength[order[start]])))
    return by_count


def classes_for_count(E, n_classes: int) -> tuple[list[tuple[int, ...]], float]:
    """The lambda-cut of E that yields ``n_classes`` classes, and its eta.

    The candidate thresholds are the distinct entries of E (between two
    consecutive entries the cut does not change).  As eta falls through them
    the number of classes falls from n towards 1.

    Parameters
    ----------
    E : array-like, shape (n, n)
        Fuzzy equivalence matrix.
    n_classes : int
        Requested number of classes, ``1 <= n_classes <= n``.

    Returns
    -------
    classes : list of tuple of int
        As :func:`lambda_cut_classes`.
    eta : float
        The largest threshold giving that partition; it is an entry of E.

    Warns
    -----
    UserWarning
        When no threshold gives exactly ``n_classes`` (ties in E merge several
        classes at one level).  Rule: take the achievable count nearest to the
        request; when two are equally near, take the larger count (the finer
        partition), so that sensors the data can still tell apart are not
        merged.  The warning names the requested and the obtained counts.
    """
    rel = _as_fuzzy_relation(E, "E")
    n = rel.shape[0]
    if isinstance(n_classes, bool) or int(n_classes) != n_classes or not (1 <= n_classes <= n):
        raise ValueError(f"n_classes must be an integer in [1, {n}], got {n_classes}")
    n_classes = int(n_classes)
    by_count = _cuts_by_count(rel)
    if n_classes in by_count:
        return by_count[n_classes]
    obtained = min(by_count, key=lambda c: (abs(c - n_classes), -c))
    warnings.warn(
        f"no lambda-cut gives {n_classes} classes (ties in the equivalence matrix); "
        f"using {obtained} class{'' if obtained == 1 else 'es'} instead (achievable counts: "
        f"{sorted(by_count)})",
        SelectionWarning,
        stacklevel=2,
    )
    return by_count[obtained]


# --------------------------------------------------------------------------- #
# the whole selection, and the two comparison rules
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class SensitivePoints:
    """Result of :func:`select_sensitive_points`.

    Attributes
    ----------
    clusters : tuple of tuple of str
        Classes of sensor ids; each in column order of X, classes ordered by
        their first sensor's column.
    selected : tuple of str
        One sensitive point per class, in column order of X.
    grades : dict of str to float
        Grade of every sensor to the target, in column order of X.
    eta : float
        Lambda-cut threshold that produced ``clusters``.
    """

    clusters: tuple[tuple[str, ...], ...]
    selected: tuple[str, ...]
    grades: dict[str, float]
    eta: float


def select_sensitive_points(
    X: pd.DataFrame,
    y,
    *,
    n_clusters: int,
    similarity: str,
    grade: str,
    rho: float,
    normalisation: str,
) -> SensitivePoints:
    """Temperature-sensitive points: fuzzy clustering, then the best-graded sensor per class.

    Parameters
    ----------
    X : pandas.DataFrame, shape (n_samples, n_sensors)
        Columns are sensor ids (e.g. ``"T1"`` ... ``"T12"``), rows are samples
        (measurements).
    y : array-like, shape (n_samples,)
        Target sequence: the slope k, the intercept b, or the error at one
        position.
    n_clusters, similarity, grade, rho, normalisation
        As config ``selection`` (:class:`thermaxis.config.SelectionSettings`) gives them.
    n_clusters : int
        Requested number of classes (3 in the paper).  If ties make it
        impossible, the nearest achievable count is used and a warning is
        issued (see :func:`classes_for_count`).
    similarity : {"pearson", "printed"}
        See :func:`similarity_matrix`.
    grade : {"deng", "absolute"}
        :func:`grey_relational_grade` (with ``rho`` and ``normalisation``) or
        :func:`absolute_grey_incidence`.
    rho, normalisation
        Passed to :func:`grey_relational_grade`; ignored for ``"absolute"``.

    Returns
    -------
    SensitivePoints
        In each class the sensor with the highest grade is kept; on equal
        grades the sensor earlier in column order wins.
    """
    names = _sensor_names(X)
    if grade not in GRADES:
        raise ValueError(f"grade must be one of {GRADES}, got {grade!r}")
    values = as_samples_by_sensors(X)
    target = as_sequence(y, values.shape[0])
    equivalence = fuzzy_equivalence(similarity_matrix(values, method=similarity))
    classes, eta = classes_for_count(equivalence, n_clusters)
    if grade == "deng":
        grades = grey_relational_grade(target, values, rho=rho, normalisation=normalisation)
    else:
        grades = absolute_grey_incidence(target, values)
    # argmax returns the first maximum, i.e. the earlier column on ties.
    best = sorted(members[int(np.argmax(grades[list(members)]))] for members in classes)
    return SensitivePoints(
        clusters=tuple(tuple(names[i] for i in members) for members in classes),
        selected=tuple(names[i] for i in best),
        grades={name: float(g) for name, g in zip(names, grades, strict=False)},
        eta=float(eta),
    )


def rank_by_correlation(X: pd.DataFrame, y, n: int) -> tuple[str, ...]:
    """The n sensors with the largest |Pearson r| with y (baseline selection).

    Parameters
    ----------
    X : pandas.DataFrame, shape (n_samples, n_sensors)
        Columns are sensor ids.
    y : array-like, shape (n_samples,)
        Target sequence.
    n : int
        Number of sensors to return, ``1 <= n <= n_sensors``.

    Returns
    -------
    tuple of str
        Ranked by decreasing |r|; equal |r| keeps column order.  A constant
        sensor counts as r = 0 (with a warning); a constant y is an error.
    """
    names = _sensor_names(X)
    values = as_samples_by_sensors(X)
    target = as_sequence(y, values.shape[0])
    if isinstance(n, bool) or int(n) != n or not (1 <= n <= len(names)):
        raise ValueError(f"n must be an integer in [1, {len(names)}], got {n}")
    unit_y, y_constant = _unit_deviations(target[:, None])
    if y_constant[0]:
        raise ValueError("y is constant: its correlation with the sensors is undefined")
    unit, constant = _unit_deviations(values)
    if constant.any():
        warnings.warn(
            f"constant sensor(s) {[names[i] for i in np.flatnonzero(constant)]}: correlation taken as 0",
            SelectionWarning,
            stacklevel=2,
        )
    abs_r = np.abs(unit.T @ unit_y[:, 0])
    order = np.argsort(-abs_r, kind="stable")
    return tuple(names[i] for i in order[: int(n)])


def common_points(
    selections: Sequence[Sequence[str]],
    n: int,
    order: Sequence[str] | None = None,
    scores: Mapping[str, float] | None = None,
) -> tuple[str, ...]:
    """The n sensors chosen most often across selections (the paper's Table 3 rule).

    Parameters
    ----------
    selections : sequence of sequence of str
        One selection per target position (a sensor repeated inside one
        selection counts once).
    n : int
        Number of sensors to return, at most the number of distinct sensors.
    order : sequence of str, optional
        Last tie-break, normally the sensor column order.  Defaults to the
        order of first appearance in ``selections``.  Must contain every
        selected sensor.
    scores : mapping of str to float, optional
        The selection's own ranking of each sensor (e.g. its mean grey relational
        grade or |r| over the positions); larger is better.  Equal counts are
        ordered by decreasing score first, so with one position (every count 1)
        the common set is the selection's best-ranked sensors, not the first
        ones by name.

    Returns
    -------
    tuple of str
        Ranked by decreasing count, then decreasing score, then position in
        ``order``.
    """
    counts: dict[str, int] = {}
    first_seen: list[str] = []
    for selection in selections:
        for sensor in dict.fromkeys(str(s) for s in selection):
            if sensor not in counts:
                counts[sensor] = 0
                first_seen.append(sensor)
            counts[sensor] += 1
    if not counts:
        raise ValueError("selections is empty: nothing to count")
    tie_order = [str(s) for s in order] if order is not None else first_seen
    position = {sensor: i for i, sensor in reversed(list(enumerate(tie_order)))}
    missing = [s for s in first_seen if s not in position]
    if missing:
        raise ValueError(
            f"order lacks selected sensor(s) {missing}; pass the full sensor column order"
        )
    if isinstance(n, bool) or int(n) != n or not (1 <= n <= len(counts)):
        raise ValueError(
            f"n must be an integer in [1, {len(counts)}] (distinct sensors selected), got {n}"
        )
    score = {sensor: float((scores or {}).get(sensor, 0.0)) for sensor in counts}
    score = {sensor: value if np.isfinite(value) else 0.0 for sensor, value in score.items()}
    ranked = sorted(counts, key=lambda s: (-counts[s], -score[s], position[s]))
    return tuple(ranked[: int(n)])


def informative_sensors(
    temperatures: pd.DataFrame, fixed: tuple[str, ...], where: str
) -> list[str]:
    """Sensors that vary over the samples; a constant one is named and left out.

    A constant series has no correlation with anything (the fuzzy relation would hold
    NaN), so it cannot be selected; a fixed sensitive point that is constant is an error.
    """
    if len(temperatures) < 2:
        raise DataError(
            f"{where}: {len(temperatures)} training measurement; selection and models need at least 2"
        )
    spread = temperatures.max() - temperatures.min()
    constant = [str(s) for s in temperatures.columns if not spread[s] > 0]
    fixed_constant = [s for s in constant if s in fixed]
    if fixed_constant:
        raise DataError(
            "config selection.fixed: "
            f"sensor {fixed_constant[0]} is constant over the training measurements; "
            "expected a sensor whose temperature varies"
        )
    if len(constant) == len(temperatures.columns):
        raise DataError(
            f"{where}: every sensor is constant over the training measurements; "
            "expected temperatures that vary"
        )
    for sensor in constant:
        warnings.warn(
            f"{where}: sensor {sensor} is constant over the training measurements; left out of the selection",
            SelectionWarning,
            stacklevel=2,
        )
    return [str(s) for s in temperatures.columns if str(s) not in constant]
