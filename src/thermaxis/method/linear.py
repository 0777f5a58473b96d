"""A numpy core for many linear fits at once: sensitive-point subsets x conditions x outputs.

Every linear model of the pipeline is ``make_regressor(algorithm)``: ``StandardScaler``
followed by ``TransformedTargetRegressor(regressor, transformer=StandardScaler())`` with
``LinearRegression`` (mlr), ``Ridge(alpha)`` (ridge) or ``PLSRegression(n_components,
scale=False)`` (pls), one pipeline per output (target position, or slope k / intercept b).
The sweep fits that pipeline for every sensitive-point subset and every held-out condition;
the arithmetic is tiny and the cost is per-call overhead.  Here the same fits come from
centred cross-product (Gram) matrices formed once per fold, with every subset's small
system solved in one batched call and all held-out measurements predicted in one product.

All three algorithms are exact: coefficients and predictions equal scikit-learn's pipeline
within 1e-9 (relative) wherever the Gram solve is accurate to that.  Where it may not be,
the (fold, subset) pair is refitted by scikit-learn itself (the fallback; ``refitted``
marks those pairs), so the numbers stay scikit-learn's:

* mlr and ridge: the eigenvalue ratio of the subset's standardised system (Z'Z, plus
  alpha I for ridge) exceeds ``COND_LIMIT`` (1e5).  Solving from the Gram matrix squares
  the condition number of the data, and its error grows with that ratio (measured: 2e-10
  of the largest slope at 4e5), so past 1e5 it can no longer promise 1e-9 with a margin;
  the twin's and fl_thermal's 3-sensor subsets stay below 8e4.  This covers singular
  systems, e.g. two sensitive points that read the same temperature (a duplicated
  column), where ``LinearRegression``'s ``scipy.linalg.lstsq`` (cond = its ``tol``,
  1e-6) returns the truncated minimum-norm solution.  Nothing is refused.
* pls: a component whose covariance with the residual target fell below ``PLS_LIMIT``
  (1e-5) of the first component's, or whose score variance below ``PLS_LIMIT`` of the
  subset's total standardised variance: the deflated Gram matrix has then lost the
  digits scikit-learn's deflation of the data keeps (this also covers its "y residual
  is constant" stop).  ``n_components`` is capped at the subset size, as ``make_regressor``
  caps it at the number of inputs.

StandardScaler's conventions are kept: population variance (ddof=0), and a feature it
judges constant (its ``_is_constant_feature`` bound) keeps scale 1; such a sensor has slope
0 in every algorithm, and a constant output has slopes 0 and intercept its mean (scikit-
learn leaves rounding-level values there).  Inputs must be finite.

Leave-one-condition-out: each fold's training statistics (counts, means, centred cross
products of sensors and outputs) are the full data's DOWNDATED by the held-out
condition's, with the pooled-covariance update of Chan, Golub & LeVeque; the scaler of each
fold is therefore that of its training measurements, as in the pipeline.  A fold whose
downdate cancels more than two digits of some variance (the held-out condition carries
most of a sensor's variation, or the sensor is constant in the training measurements) is
summed from its training rows instead.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from typing import NamedTuple

import numpy as np

from thermaxis.errors import raise_again, recorded
from thermaxis.method.scaling import is_constant, mean_variance

__all__ = [
    "ALGORITHMS",
    "COND_LIMIT",
    "PLS_LIMIT",
    "LinearFit",
    "loco_fit",
    "standardised_fit",
    "subset_fit",
]

ALGORITHMS = ("mlr", "ridge", "pls")
COND_LIMIT = 1e5
PLS_LIMIT = 1e-5
# A downdated variance may be this many times smaller than the full data's before the
# fold is summed from its rows (cancellation costs log10 of the ratio in digits).
_DOWNDATE_LOSS = 100.0


class LinearFit(NamedTuple):
    """Fitted affine maps in original units: ``prediction = intercept + x[subset] @ slopes``.

    Leading axes: (folds, subsets) for :func:`loco_fit`, (subsets,) for :func:`subset_fit`,
    none for :func:`standardised_fit`; the last axis of ``intercept`` and ``slopes`` is
    the output (m), ``slopes`` has the subset's sensors before it.  ``predictions`` are
    (rows, subsets, m), rows first like ``Y`` ((rows, m) for :func:`standardised_fit`).
    ``refitted`` marks the (fold, subset) pairs that scikit-learn refitted (module notes).
    """

    intercept: np.ndarray
    slopes: np.ndarray
    predictions: np.ndarray | None
    refitted: np.ndarray


# --------------------------------------------------------------------------- public


def standardised_fit(
    X, Y, algorithm: str, *, alpha: float = 1.0, n_components: int = 2
) -> LinearFit:
    """One pipeline per output column of ``Y`` on all columns of ``X``, at once.

    ``X`` (n, p) sensors, ``Y`` (n, m) outputs (a 1-D ``Y`` is one output).  Returns
    intercept (m,), slopes (p, m), the fitted values (n, m) and ``refitted`` (a 0-d bool).
    """
    X, Y = _check_xy(X, Y)
    fit = subset_fit(
        X, Y, [np.arange(X.shape[1])], algorithm, alpha=alpha, n_components=n_components, X_new=X
    )
    return LinearFit(fit.intercept[0], fit.slopes[0], fit.predictions[:, 0], fit.refitted[0])


def subset_fit(
    X, Y, subsets, algorithm: str, *, alpha: float = 1.0, n_components: int = 2, X_new=None
) -> LinearFit:
    """Every sensitive-point subset fitted on all rows; optionally predict rows ``X_new``.

    ``subsets`` (q, s): column indices of ``X``, every subset the same size.  Returns
    intercept (q, m), slopes (q, s, m), predictions (len(X_new), q, m) or None, refitted (q,).
    """
    X, Y = _check_xy(X, Y)
    subsets = _check_subsets(subsets, X.shape[1])
    rows = np.arange(X.shape[0])
    stats = [_moments(np.hstack([X, Y]))]
    intercept, slopes, level, centre, refitted = _fit_folds(
        X, Y, [rows], stats, subsets, algorithm, alpha, n_components
    )
    predictions = None
    if X_new is not None:
        X_new = np.asarray(X_new, dtype=float)
        if X_new.ndim != 2 or X_new.shape[1] != X.shape[1] or not np.isfinite(X_new).all():
            raise ValueError(
                f"X_new must be a finite 2-D array with {X.shape[1]} columns, got shape {X_new.shape}"
            )
        predictions = _predict(X_new, subsets, level[0], centre[0], slopes[0])
    return LinearFit(intercept[0], slopes[0], predictions, refitted[0])


def loco_fit(
    X, Y, groups, subsets=None, algorithm: str = "mlr", *, alpha: float = 1.0, n_components: int = 2
) -> tuple[np.ndarray, LinearFit]:
    """Leave-one-condition-out: every (held-out condition, subset) pair in one call.

    ``groups`` (n,) labels the condition (run) of each row; folds follow ``np.unique``
    order, as ``LeaveOneGroupOut``.  ``subsets`` (q, s) as in :func:`subset_fit`; None
    is one subset of all columns.  Returns the fold labels (F,) and a :class:`LinearFit`
    with intercept (F, q, m), slopes (F, q, s, m), refitted (F, q) and predictions
    (n, q, m): each row predicted by the fold that held its condition out.
    """
    X, Y = _check_xy(X, Y)
    subsets = _check_subsets(
        np.arange(X.shape[1])[None, :] if subsets is None else subsets, X.shape[1]
    )
    groups = np.asarray(groups)
    if groups.shape != (X.shape[0],):
        raise ValueError(
            f"groups must hold one label per row ({X.shape[0]}), got shape {groups.shape}"
        )
    labels, fold_of_row = np.unique(groups, return_inverse=True)
    if len(labels) < 2:
        raise ValueError(f"leave-one-condition-out needs at least 2 conditions, got {len(labels)}")
    W = np.hstack([X, Y])
    full = _moments(W)
    stats, train_rows = [], []
    for f in range(len(labels)):
        held = fold_of_row == f
        train_rows.append(np.flatnonzero(~held))
        stats.append(_downdate(full, _moments(W[held]), W, ~held))
    intercept, slopes, level, centre, refitted = _fit_folds(
        X, Y, train_rows, stats, subsets, algorithm, alpha, n_components
    )
    predictions = np.empty((X.shape[0], len(subsets), Y.shape[1]))
    for f in range(len(labels)):
        held = fold_of_row == f
        predictions[held] = _predict(X[held], subsets, level[f], centre[f], slopes[f])
    return labels, LinearFit(intercept, slopes, predictions, refitted)


# --------------------------------------------------------------------------- statistics


def _check_xy(X, Y):
    X = np.asarray(X, dtype=float)
    Y = np.asarray(Y, dtype=float)
    if Y.ndim == 1:
        Y = Y[:, None]
    if X.ndim != 2 or Y.ndim != 2 or X.shape[0] != Y.shape[0] or X.shape[0] < 2:
        raise ValueError(
            f"X (n, p) and Y (n, m) must share n >= 2 rows, got shapes {X.shape} and {Y.shape}"
        )
    if not (np.isfinite(X).all() and np.isfinite(Y).all()):
        raise ValueError(
            "X and Y must be finite; drop or fill missing readings before the linear core"
        )
    return X, Y


def _check_subsets(subsets, p: int) -> np.ndarray:
    try:
        subsets = np.asarray(subsets, dtype=np.intp)
    except ValueError as exc:
        raise ValueError("subsets must all have the same size") from exc
    if subsets.ndim != 2 or subsets.shape[0] == 0 or subsets.shape[1] == 0:
        raise ValueError(
            f"subsets must be a non-empty (q, s) array of column indices, got shape {subsets.shape}"
        )
    if subsets.min() < 0 or subsets.max() >= p:
        raise ValueError(f"subset column indices must lie in 0..{p - 1}")
    return subsets


def _moments(W):
    """Count, mean, centred cross products and StandardScaler's variance of the rows W.

    The mean and the variance are StandardScaler's own numbers (:func:`mean_variance`), so
    that its constant-feature test sees them; cross products are of centred data, never raw
    sums.
    """
    n, mean, Wc, variance = mean_variance(W)
    return n, mean, Wc.T @ Wc, variance


def _downdate(full, held, W, train):
    """Training statistics of a fold: the full data's minus the held-out condition's.

    Chan's pooled update S = S_train + S_held + (n_train n_held / n) e e', with
    e = mean_held - mean_train = d n / n_train for d = mean_held - mean, solved for S_train.
    """
    n, mean, S, _ = full
    n_held, mean_held, S_held, _ = held
    n_t = n - n_held
    d = mean_held - mean
    S_t = S - S_held - (n * n_held / n_t) * np.outer(d, d)
    diag = np.diag(S_t)
    if np.any(diag * _DOWNDATE_LOSS <= np.diag(S)):
        return _moments(W[train])
    return n_t, mean - (n_held / n_t) * d, S_t, diag / n_t


# --------------------------------------------------------------------------- solving


def _fit_folds(X, Y, train_rows, stats, subsets, algorithm, alpha, n_components):
    if algorithm not in ALGORITHMS:
        raise ValueError(
            f"unknown linear algorithm {algorithm!r}; expected one of {', '.join(ALGORITHMS)}"
        )
    if algorithm == "ridge" and not alpha >= 0:
        raise ValueError(f"ridge alpha must be >= 0, got {alpha}")
    p, s = X.shape[1], subsets.shape[1]
    k = min(int(n_components), s)
    if algorithm == "pls" and (k < 1 or any(st[0] < k for st in stats)):
        raise ValueError(f"pls needs 1 <= n_components <= training rows, got {n_components}")
    n_t, mean, constant, scale, A, B = _standardised_systems(stats, p)
    # Every subset's block, gathered for all folds: (F, q, s, s) and (F, q, s, m).
    A = A[:, subsets[:, :, None], subsets[:, None, :]]
    B = B[:, subsets, :]
    fixed = constant[:, subsets]  # (F, q, s): sensitive points constant in the fold
    if algorithm == "pls":
        w, refitted = _pls_gram(A, B, k)
    else:
        w, refitted = _normal_equations(A, B, fixed, n_t, alpha if algorithm == "ridge" else 0.0)
    w = np.where(fixed[..., None], 0.0, w)
    slopes = w / scale[:, subsets][..., None]
    level = np.broadcast_to(
        mean[:, None, p:], w.shape[:2] + (Y.shape[1],)
    ).copy()  # prediction at the centre
    centre = mean[:, subsets]
    for f, q in zip(*np.nonzero(refitted), strict=False):
        level[f, q], slopes[f, q], centre[f, q] = _sklearn_fit_once(
            X[train_rows[f]][:, subsets[q]], Y[train_rows[f]], algorithm, alpha, k
        )
    intercept = level - np.einsum("fqs,fqsm->fqm", centre, slopes)
    return intercept, slopes, level, centre, refitted


def _standardised_systems(stats, p: int):
    """Each fold's standardised system of every sensor from its training statistics.

    Returns the training row counts (F,), the means (F, p + m), which columns are
    constant, the sensors' scales (F, p), and Z'Z (F, p, p) and Z'y (F, p, m).
    """
    n_t = np.array([st[0] for st in stats], dtype=float)  # (F,)
    mean = np.stack([st[1] for st in stats])  # (F, p + m)
    S = np.stack([st[2] for st in stats])
    variance = np.stack([st[3] for st in stats])
    constant = is_constant(variance, mean, n_t[:, None])
    scale = np.where(constant, 1.0, np.sqrt(variance))[:, :p]
    # The standardised system of every sensor (Z'Z with Z = (x - mean) / scale, Z'y); a
    # constant sensor's row and column are zero, a constant output's column too.
    A = S[:, :p, :p] / (scale[:, :, None] * scale[:, None, :])
    B = S[:, :p, p:] / scale[:, :, None]
    A = np.where(constant[:, :p, None] | constant[:, None, :p], 0.0, A)
    B = np.where(constant[:, :p, None] | constant[:, None, p:], 0.0, B)
    return n_t, mean, constant, scale, A, B


def _normal_equations(A, B, fixed, n_t, alpha):
    """Least squares (alpha 0) or ridge from each subset's standardised Gram matrix.

    A constant sensor's equation becomes ``n w = 0`` so it neither gets a slope nor
    changes the condition number.  Solved by a batched symmetric eigendecomposition, whose
    eigenvalues also flag the systems past ``COND_LIMIT``.
    """
    eye = np.eye(A.shape[-1], dtype=bool)
    A = A + np.where(fixed[..., None] & eye, n_t[:, None, None, None], 0.0) + alpha * eye
    lam, V = np.linalg.eigh(A)
    refitted = ~(lam[..., :1] * COND_LIMIT > lam[..., -1:])[..., 0]
    lam = np.where(refitted[..., None], 1.0, lam)
    w = V @ ((np.swapaxes(V, -1, -2) @ B) / lam[..., None])
    return w, refitted


def _pls_gram(G, C, k):
    """PLSRegression's NIPALS (PLS1, one per output) run on the Gram matrices.

    Deflating the data X_j+1 = X_j - t p' deflates its Gram matrix G_j+1 = G_j - (t't) p p'
    and the cross products c_j+1 = c_j - p (t'y_j).  The weights' length does not reach
    the coefficient W (P'W)^-1 q, so scikit-learn's normalisation (and its sign flip) are
    left out.
    """
    c = np.swapaxes(C, -1, -2)  # (F, q, m, s): one PLS1 per output
    G = np.broadcast_to(G[..., None, :, :], c.shape + c.shape[-1:])
    c_first = np.linalg.norm(c, axis=-1)
    g_scale = np.trace(G, axis1=-2, axis2=-1)
    zero = c_first == 0  # a constant output (or only constant sensors): slopes 0
    weak = np.zeros(c.shape[:-1], dtype=bool)
    weights, loadings, y_loadings = [], [], []
    for _ in range(k):
        norm = np.linalg.norm(c, axis=-1)
        weak |= norm <= PLS_LIMIT * c_first
        w = c / np.where(norm > 0, norm, 1.0)[..., None]
        Gw = np.einsum("...ij,...j->...i", G, w)
        tt = np.einsum("...i,...i->...", w, Gw)
        weak |= tt <= PLS_LIMIT * g_scale
        tt = np.where(tt > 0, tt, 1.0)
        ty = np.einsum("...i,...i->...", c, w)
        p = Gw / tt[..., None]
        G = G - tt[..., None, None] * p[..., :, None] * p[..., None, :]
        c = c - p * ty[..., None]
        weights.append(w)
        loadings.append(p)
        y_loadings.append(ty / tt)
    W = np.stack(weights, axis=-1)  # (F, q, m, s, k)
    P = np.stack(loadings, axis=-1)
    q = np.stack(y_loadings, axis=-1)[..., None]
    weak &= ~zero
    PW = np.swapaxes(P, -1, -2) @ W
    PW = np.where((weak | zero)[..., None, None], np.eye(k), PW)
    b = (W @ np.linalg.solve(PW, q))[..., 0]  # (F, q, m, s)
    b = np.where(zero[..., None], 0.0, b)
    return np.swapaxes(b, -1, -2), weak.any(axis=-1)


def _predict(X_rows, subsets, level, centre, slopes):
    """All subsets' predictions of the rows in one product, (rows, q, m), centred form."""
    deviation = X_rows[:, subsets] - centre[None, :, :]  # (rows, q, s)
    predictions = np.einsum("nqs,qsm->nqm", deviation, slopes)
    predictions += level[None, :, :]
    return predictions


# The nested recommendation fits the same training runs again and again: an outer fold's
# inner split and another outer fold's often leave the same runs out (on 5 runs x 22
# sensors, 775 fallback fits were 245 distinct ones). A fallback fit is a pure function of
# its inputs, so the last FALLBACK_MEMO distinct ones are kept, with the warnings they
# raised, which a reuse raises again: a job's warnings do not depend on what this process
# fitted before.
FALLBACK_MEMO = 4096
_fallback_fits: OrderedDict = OrderedDict()


def _sklearn_fit_once(Xs, Y, algorithm, alpha, k):
    """:func:`_sklearn_fit`, looked up when the same inputs were fitted before."""
    # The memory layout is part of the key: scikit-learn's rounding follows it.
    digest = hashlib.sha256(Xs.tobytes(order="A") + Y.tobytes(order="A")).digest()
    layout = tuple(
        (a.dtype.str, a.shape, a.flags.c_contiguous, a.flags.f_contiguous) for a in (Xs, Y)
    )
    key = (digest, layout, algorithm, float(alpha), int(k))
    if key in _fallback_fits:
        _fallback_fits.move_to_end(key)
    else:
        _fallback_fits[key] = recorded(_sklearn_fit, Xs, Y, algorithm, alpha, k)
        if len(_fallback_fits) > FALLBACK_MEMO:
            _fallback_fits.popitem(last=False)
    fit, raised = _fallback_fits[key]
    raise_again(raised)
    return tuple(a.copy() for a in fit)


def _sklearn_fit(Xs, Y, algorithm, alpha, k):
    """scikit-learn's pipelines on one (fold, subset) pair, as (level, slopes, centre).

    One pipeline per output, as the models fit them: on a singular system even mlr's and
    ridge's rounding differs between one output and several.
    """
    from thermaxis.method.regressors import checked_once, make_regressor

    s, m = Xs.shape[1], Y.shape[1]
    params = {"ridge": {"alpha": alpha}, "pls": {"n_components": k}}.get(algorithm)
    pipelines = [make_regressor(algorithm, params, random_state=0, n_features=s) for _ in range(m)]
    level, slopes = np.empty(m), np.empty((s, m))
    with checked_once([pipelines[0].named_steps["regress"].regressor], Xs, Y):
        # Every output's pipeline standardises the same inputs: they are standardised once,
        # as the pipeline does it, and each output's target step is fitted on them.
        scaler = pipelines[0].named_steps["standardise"].fit(Xs)
        standardised = scaler.transform(Xs)
        for j, pipeline in enumerate(pipelines):
            regress = pipeline.named_steps["regress"].fit(standardised, Y[:, j])
            target = regress.transformer_
            # The regressor is affine in standardised units; probe it at 0 and the unit vectors.
            probe = np.ravel(regress.regressor_.predict(np.vstack([np.zeros(s), np.eye(s)])))
            level[j] = target.mean_[0] + target.scale_[0] * probe[0]
            slopes[:, j] = (probe[1:] - probe[0]) * target.scale_[0] / scaler.scale_
    return level, slopes, scaler.mean_
