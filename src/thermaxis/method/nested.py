"""Which model a user's own runs support: a nested leave-one-condition-out super learner.

The candidates are :mod:`thermaxis.method.candidates`'. The question a machine
builder asks is which model to deploy and how much error it leaves on a condition it has
not seen. Answering it honestly needs two loops:

* the *outer* loop holds out one condition (run) at a time: it is the unseen condition;
* the *inner* loop, on the remaining training runs alone, predicts each training run by
  every candidate fitted on the other training runs, one run at a time whatever the number
  of runs.

The recommendation is the super learner (van der Laan, Polley and Hubbard 2007; Breiman
1996) over a small library of linear candidates (config ``recommend.combine``): the
convex combination of the members' predicted error curves whose weights minimise the
mean RMSE of the inner held-out runs, each run counted once (config
``recommend.weighting``, :data:`WEIGHTINGS`): the loss the recommendation is judged by.
Choosing one candidate on four to six runs is noise; weighting a few structurally
different ones is steadier. Each outer fold's weights come
from its inner predictions alone, so the held-out run reaches no weight; its held-out
error is the members fitted on the training runs, so weighted. The final weights come
from every run's held-out predictions, and the deployed model is the members refitted
on all runs, so weighted: one linear model (:func:`thermaxis.compensation.model.combined_record`).
Every candidate is still scored, as information (``recommend/candidates.csv``).

Every evaluation is :func:`thermaxis.method.folds.fold_metrics` (the metrics of the
models rule's ``evaluate_configuration``) after
:func:`~thermaxis.method.folds.select_for_fold`: the functions the main workflow and the
sweep use, with sensitive points always chosen on the training runs only.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from functools import partial

import numpy as np
import pandas as pd
from scipy.optimize import minimize, nnls

from thermaxis.labels import natural_sorted
from thermaxis.method.batched import (
    batchable,
    decoupled_curves,
    decoupled_metrics,
    pointwise_curves,
    pointwise_metrics,
)
from thermaxis.method.candidates import Candidate, candidate_view
from thermaxis.method.folds import (
    _predictions,
    fit_held_out,
    fold_metrics,
    fold_name,
    held_out_runs,
    run_groups,
    select_for_fold,
)
from thermaxis.method.metrics import METRIC_COLUMNS, prediction_metrics

__all__ = [
    "Recommendation",
    "held_out_predictions",
    "held_out_scores",
    "TrainingSet",
    "training_sets",
    "training_set_scores",
    "SCORE_COLUMNS",
    "outer_fold_scores",
    "COMBINED",
    "super_learner_weights",
    "selector_weights",
    "run_rmse_weights",
    "WEIGHTINGS",
    "MIN_WEIGHING_RUNS",
    "Combination",
    "combine",
    "fold_scores",
    "collect",
    "recommend",
    "summary_of",
]


@dataclass(frozen=True)
class Recommendation:
    """The outcome: per outer fold the combination and its honest error, and the final one.

    ``folds`` has one row per outer fold: fold, chosen (:data:`COMBINED`), weight_<member>
    (the fold's weights), rmse_um, max_abs_um (the combination on the held-out run),
    paper_rmse_um, paper_max_abs_um (the reference candidate there). ``inner`` has one row
    per outer fold x candidate x inner held-out run. ``loco`` has one row per candidate x
    run: each candidate's leave-one-condition-out error (information: every candidate is
    scored). ``combination`` holds the fold weights and the final ones.
    """

    folds: pd.DataFrame
    inner: pd.DataFrame
    loco: pd.DataFrame
    final: str
    combination: Combination


def _fold_setup(X, Y, fold, candidate, degree, signals, cache):
    """A candidate's view of X, its model settings and its selection on the training rows.

    Candidates that differ only in their algorithm share the selection (``cache``), as the
    main workflow's algorithms share a fold's; so do evaluations on the same training runs.
    """
    view, selectable, models = candidate_view(X, candidate, signals)
    # The recommendation never lets the held-out run into the choice of sensitive points.
    selection_settings = replace(candidate.selection, scope="training")
    decoupled = candidate.approach == "decoupled"
    held = set(held_out_runs(fold))
    key = (
        tuple(sorted(r for r in pd.unique(X["run"]) if r not in held)),
        tuple(selectable),
        selection_settings,
        decoupled,
    )
    if key not in cache:
        cache[key] = select_for_fold(
            view[selectable], Y, fold, selection_settings, degree if decoupled else None,
            decoupled=decoupled, pointwise=not decoupled,
        )  # fmt: skip
    return view, models, cache[key]


def _curves(view, Y, fold, candidate, models, selection, degree) -> np.ndarray:
    """The error curves of ``fold``'s rows (in X's order) predicted by ``candidate`` fitted
    on the other rows of ``view``: the numpy core where it applies, else the estimator."""
    if batchable(candidate.algorithm, models, Y):
        if candidate.approach == "decoupled":
            return decoupled_curves(view, Y, fold, candidate.algorithm, models, degree,
                                    selection.k_sensors, selection.b_sensors)  # fmt: skip
        return pointwise_curves(view, Y, fold, candidate.algorithm, models, selection.pointwise)
    decoupled = candidate.approach == "decoupled"
    estimator, X_test, Y_test = fit_held_out(
        view, Y, fold, candidate.approach, candidate.algorithm, selection, models,
        degree if decoupled else None,
    )  # fmt: skip
    return _predictions(estimator, X_test, Y_test, candidate.approach, degree)[2]


def _error_metrics(X, Y, fold, candidate, degree, signals, cache, keep=False):
    """Select on the training rows of X, fit, predict ``fold``: its error metrics.

    ``fold`` is a run or a group of runs, fitted once: ``([(run, metrics), ...], curves)``
    for each of its runs, ``curves`` the predicted error curves of its rows with ``keep``
    (a member of the combination), else None.
    """
    view, models, selection = _fold_setup(X, Y, fold, candidate, degree, signals, cache)
    decoupled = candidate.approach == "decoupled"
    if keep:
        # One fit gives the curves the weights are fitted on and the member's scores.
        curves = _curves(view, Y, fold, candidate, models, selection, degree)
        test = X["run"].isin(held_out_runs(fold)).to_numpy()
        runs, measured = X.loc[test, "run"].to_numpy(), Y.loc[test].to_numpy(dtype=float)
        scored = [
            (run, prediction_metrics(measured[runs == run], curves[runs == run]))
            for run in pd.unique(runs)
        ]
        return [
            (run, {name: float(m[name]) for name in METRIC_COLUMNS}) for run, m in scored
        ], curves
    if batchable(candidate.algorithm, models, Y):
        # The numpy core: the same numbers as evaluate_configuration to 1e-9.
        (metrics,) = (
            decoupled_metrics(view, Y, fold, candidate.algorithm, models, degree,
                              [(selection.k_sensors, selection.b_sensors)], per_run=True)
            if decoupled
            else pointwise_metrics(view, Y, fold, candidate.algorithm, models,
                                   [selection.pointwise], per_run=True)
        )  # fmt: skip
    else:
        metrics = fold_metrics(
            view, Y, fold, candidate.approach, candidate.algorithm, selection, models,
            degree if decoupled else None, per_run=True,
        )  # fmt: skip
    errors = metrics.loc[metrics["target"] == "error"]
    return [
        (row["fold"], {name: float(row[name]) for name in METRIC_COLUMNS})
        for _, row in errors.iterrows()
    ], None


def held_out_predictions(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    fold: Sequence[str],
    candidate: Candidate,
    degree: int,
    signals: Sequence[str],
    cache: dict,
) -> tuple[np.ndarray, np.ndarray]:
    """The error curves of the runs ``fold`` predicted by ``candidate`` fitted on the rest of X.

    ``(run of each held-out row, predictions (rows, positions))``, the rows in X's order,
    selected and fitted as :func:`held_out_scores` scores them (what a combination of
    candidates is fitted on and judged by).
    """
    view, models, selection = _fold_setup(X, Y, fold, candidate, degree, signals, cache)
    test = X["run"].isin(held_out_runs(fold)).to_numpy()
    return X.loc[test, "run"].to_numpy(), _curves(
        view, Y, fold, candidate, models, selection, degree
    )


def held_out_scores(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    train_runs: Sequence[str],
    held_out: Sequence[Sequence[str]],
    candidate: Candidate,
    degree: int,
    signals: Sequence[str],
    cache: dict,
) -> list[dict]:
    """Each held-out run's error when ``candidate`` is fitted on the rest of ``train_runs``.

    Each group of ``held_out`` is fitted once and scored run by run: one fit per group,
    not per run. Rows of X and Y outside ``train_runs`` are never seen: not by the
    selection, the fit or the scaling.
    """
    keep = X["run"].isin(train_runs).to_numpy()
    X, Y = X.loc[keep].reset_index(drop=True), Y.loc[keep].reset_index(drop=True)
    rows = []
    for group in held_out:
        scored, _ = _error_metrics(X, Y, group, candidate, degree, signals, cache)
        for name, metrics in scored:
            rows.append({"candidate": candidate.name, "held_out": name, **metrics})
    return rows


@dataclass(frozen=True)
class TrainingSet:
    """The evaluations that fit on the same training runs, done with one fit per candidate.

    With leave-one-out on both loops, the inner fold of outer fold E3 that holds out E4
    and the inner fold of outer fold E4 that holds out E3 both train on the other runs:
    half the inner fits repeat one another. ``scored`` are the held-out runs, each scored
    on its own, from one fit (an outer group's runs, and the inner loops' single runs).
    """

    train: tuple[str, ...]
    scored: tuple[str, ...]


def _outer_splits(runs, fold):
    """An outer fold's held-out runs, its training runs and its inner held-out runs.

    The inner loop leaves one training run out at a time at every size: each run is one
    paired piece of evidence, and on the linear core a fit costs little, so none is
    pooled into a group fold (a kernel candidate is capped instead, ``kernel_max_runs``).
    """
    held = held_out_runs(fold)
    train = [r for r in runs if r not in held]
    # With two runs the training side of a fold is one run: nothing to compare candidates
    # on without the held-out run, so the fold has no inner scores (collect says so).
    splits = [(run,) for run in train] if len(train) >= 2 else []
    return held, train, splits


def training_sets(runs: Sequence[str], folds: Sequence[str | Sequence[str]]) -> list[TrainingSet]:
    """Every distinct set of training runs the outer ``folds`` and their inner loops fit on.

    In the order first needed, outer folds in turn; :func:`outer_fold_scores` puts
    their scores back into the folds' rows.
    """
    runs = natural_sorted(runs)
    needed: dict[tuple[str, ...], dict[str, None]] = {}
    for fold in folds:
        held, train, splits = _outer_splits(runs, fold)
        needed.setdefault(tuple(train), {}).update(dict.fromkeys(held))
        for (run,) in splits:
            needed.setdefault(tuple(r for r in train if r != run), {})[run] = None
    return [TrainingSet(train, tuple(scored)) for train, scored in needed.items()]


def training_set_scores(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    candidates: Sequence[Candidate],
    training: TrainingSet,
    degree: int,
    signals: Sequence[str] = (),
    progress: Callable[[str], None] | None = None,
    members: Sequence[str] = (),
) -> tuple[dict[tuple[str, str], dict], dict[tuple[str, str], np.ndarray]]:
    """Every candidate fitted once on ``training.train``, scored on each held-out run.

    ``({(candidate, run): metrics}, {(member, run): predicted error curves})``: the
    held-out runs share one fit; the curves are kept for the ``members`` of the
    combination alone, from the same fit as their scores.
    """
    say = progress or (lambda message: None)
    keep = X["run"].isin([*training.train, *training.scored]).to_numpy()
    X, Y = X.loc[keep].reset_index(drop=True), Y.loc[keep].reset_index(drop=True)
    runs = X.loc[X["run"].isin(training.scored), "run"].to_numpy()
    cache: dict = {}
    scores, curves = {}, {}
    for candidate in candidates:
        say(f"training runs {fold_name(training.train)}: {candidate.name}")
        member = candidate.name in members
        scored, predicted = _error_metrics(
            X, Y, training.scored, candidate, degree, signals, cache, keep=member
        )
        for run, metrics in scored:
            scores[(candidate.name, run)] = metrics
            if member:
                curves[(candidate.name, run)] = predicted[runs == run]
    return scores, curves


SCORE_COLUMNS = ["kind", "fold", "candidate", "held_out", *METRIC_COLUMNS]


def outer_fold_scores(
    runs: Sequence[str],
    candidates: Sequence[Candidate],
    fold: str | Sequence[str],
    scores: Mapping[tuple[str, ...], Mapping[tuple[str, str], dict]],
) -> pd.DataFrame:
    """Everything one outer fold contributes, from its training sets' ``scores``.

    ``fold`` is a run, or a group of runs held out together: above
    ``recommend.max_loco_runs`` runs the outer loop deals them into groups
    (:func:`~thermaxis.method.folds.run_groups`), because leaving each run out would repeat
    the whole inner loop per run, a cost that grows with the square of the runs. Every run
    is still held out once; its row is its group's choice, fitted on the runs outside. Rows
    of kind ``inner``: each candidate fitted on the training runs but one, scored on that
    run (the fold's runs are in none of them), repeated under each run of the fold. Rows of kind ``loco``: each candidate fitted on every run outside the
    fold, scored on each of its runs. ``scores`` maps each training set's runs to
    :func:`training_set_scores`.
    """
    held, train, splits = _outer_splits(natural_sorted(runs), fold)
    rows: dict[str, list] = {run: [] for run in held}
    for c in candidates:
        for run in held:
            metrics = scores[tuple(train)][(c.name, run)]
            rows[run].append({"kind": "loco", "fold": run, "candidate": c.name,
                              "held_out": run, **metrics})  # fmt: skip
        for group in splits:
            rest, name = tuple(r for r in train if r not in group), fold_name(group)
            metrics = scores[rest][(c.name, name)]
            for run in held:
                rows[run].append({"kind": "inner", "fold": run, "candidate": c.name,
                                  "held_out": name, **metrics})  # fmt: skip
    return pd.DataFrame([r for run in held for r in rows[run]], columns=SCORE_COLUMNS)


COMBINED = "super learner"


def super_learner_weights(predictions: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """Non-negative least-squares weights of the columns of ``predictions``, summing to one.

    ``predictions`` (n, members), ``measured`` (n,), pairs with a missing measurement left
    out. The super learner's ``method.NNLS`` (van der Laan, Polley and Hubbard 2007;
    Breiman 1996): all zero (no member helps) gives equal weights, as SuperLearner does.
    """
    finite = np.isfinite(measured)
    weights, _ = nnls(predictions[finite], measured[finite])
    total = weights.sum()
    return weights / total if total > 0 else np.full(weights.size, 1.0 / weights.size)


@dataclass(frozen=True)
class Combination:
    """The super learner's weights: ``folds`` per held-out run (its outer fold's, fitted on
    that fold's inner predictions), ``final`` on every run's held-out predictions; each in
    the order of ``members``. ``equal_folds`` are the held-out runs whose fold weights its
    members equally; ``final_fitted``, whether the final weights were fitted."""

    members: tuple[str, ...]
    folds: Mapping[str, tuple[float, ...]]
    final: tuple[float, ...]
    equal_folds: tuple[str, ...]
    final_fitted: bool


def _runs_read(predictions, measured) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each run's (predictions, measured) with its missing measurements left out; a run
    with none is dropped."""
    runs = []
    for p, m in zip(predictions, measured, strict=True):
        keep = np.isfinite(m)
        if keep.any():
            runs.append((p[keep], m[keep]))
    return runs


def _run_mse_and_slope(p, m, w) -> tuple[float, np.ndarray]:
    """A run's mean squared error q of the weighted members ``w`` and half its gradient,
    from the residuals themselves: near an exact fit, w'Aw - 2b'w + c would cancel."""
    residual = m - p @ w
    return float(residual @ residual) / m.size, -(p.T @ residual) / m.size


def _mean_run_rmse(runs, w) -> float:
    # The objective alone: SLSQP asks for it more often than for the gradient.
    return float(np.mean([np.sqrt(np.mean((m - p @ w) ** 2)) for p, m in runs]))


def _mean_run_rmse_gradient(runs, w) -> np.ndarray:
    # d sqrt(q)/dw = (half the gradient of q) / sqrt(q); a run predicted exactly has none.
    gradient = np.zeros(w.size)
    for p, m in runs:
        q, d = _run_mse_and_slope(p, m, w)
        gradient += d / max(np.sqrt(q), 1e-300)
    return gradient / len(runs)


def selector_weights(
    predictions: Sequence[np.ndarray], measured: Sequence[np.ndarray]
) -> np.ndarray:
    """All the weight on the member of the lowest mean RMSE over the held-out runs.

    ``predictions`` per run (n_r, members), ``measured`` per run (n_r,), a missing
    measurement left out. Each run's RMSE counts once, as the recommendation's held-out
    error does (a long run does not outvote a short one); a tie goes to the first member.
    The discrete super learner, the cross-validation selector of van der Laan, Polley and
    Hubbard (2007).
    """
    runs = _runs_read(predictions, measured)
    vertices = np.eye(predictions[0].shape[1])
    return vertices[int(np.argmin([_mean_run_rmse(runs, v) for v in vertices]))]


def run_rmse_weights(
    predictions: Sequence[np.ndarray], measured: Sequence[np.ndarray]
) -> np.ndarray:
    """Non-negative weights summing to one of the lowest mean RMSE over the held-out runs.

    As :func:`selector_weights`, over every convex combination: the super learner under
    the loss the recommendation is judged by, each run's RMSE counted once (van der Laan,
    Polley and Hubbard 2007 allow any loss). The mean of the runs' RMSEs is convex in the
    weights (each is the norm of an affine function of them), so a local minimum on the
    simplex is the minimum; SLSQP is started from the equal weights and from each member
    alone, and the best point found is kept, a member alone on a tie (the first).
    """
    runs = _runs_read(predictions, measured)
    n_members = predictions[0].shape[1]
    points = list(np.eye(n_members))
    for start in [np.full(n_members, 1.0 / n_members), *np.eye(n_members)]:
        found = minimize(
            partial(_mean_run_rmse, runs),
            start,
            jac=partial(_mean_run_rmse_gradient, runs),
            method="SLSQP",
            bounds=[(0.0, 1.0)] * n_members,
            constraints=[{"type": "eq", "fun": lambda w: w.sum() - 1.0,
                          "jac": lambda w: np.ones_like(w)}],
            options={"ftol": 1e-12, "maxiter": 500},
        )  # fmt: skip
        w = np.clip(found.x, 0.0, None)
        points.append(w / w.sum())
    risks = [_mean_run_rmse(runs, w) for w in points]
    return _polished(runs, points[int(np.argmin(risks))])


def _polished(runs, w: np.ndarray) -> np.ndarray:
    """``w`` taken by Newton's method to the minimum on the face of the simplex it lies on.

    SLSQP stops once the risk changes by less than its tolerance, which fixes the weights
    to about the square root of it, and OpenBLAS's kernels of another CPU stop it
    elsewhere; Newton's steps on the face's stationarity condition take the weights to
    their last digits. Where the face is flat (members that predict alike) or a run is
    predicted exactly (no curvature), ``w`` stays.
    """
    face = np.flatnonzero(w > 1e-9)
    if face.size < 2:
        return w
    Z = np.vstack([np.eye(face.size - 1), -np.ones(face.size - 1)])  # directions along the face
    v = np.zeros_like(w)
    v[face] = w[face] / w[face].sum()
    for _ in range(50):
        gradient, hessian = np.zeros(w.size), np.zeros((w.size, w.size))
        for p, m in runs:
            q, d = _run_mse_and_slope(p, m, v)
            if q <= 0.0:
                return w
            gradient += d / np.sqrt(q)
            hessian += (p.T @ p / m.size) / np.sqrt(q) - np.outer(d, d) / q**1.5
        try:
            step = Z @ np.linalg.solve(Z.T @ hessian[np.ix_(face, face)] @ Z, Z.T @ gradient[face])
        except np.linalg.LinAlgError:
            return w
        if not np.isfinite(step).all() or (v[face] - step < 0.0).any():
            return w
        v[face] -= step
        if np.abs(step).max() <= 1e-15:
            break
    better = _mean_run_rmse(runs, v) <= _mean_run_rmse(runs, w) * (1.0 + 1e-12)
    return v if better else w


def _nnls(predictions, measured) -> np.ndarray:
    return super_learner_weights(np.vstack(predictions), np.concatenate(measured))


# config recommend.weighting
WEIGHTINGS: Mapping[str, Callable[[list, list], np.ndarray]] = {
    "rmse": run_rmse_weights,
    "select": selector_weights,
    "nnls": _nnls,
}


# The fewest training runs of a fit whose held-out predictions may weigh the members: a
# member fitted on one run has seen one condition, which says little of fits on two or more
# (on three-run records such weights did worse than equal ones: docs/recommendation.md).
MIN_WEIGHING_RUNS = 2


def _weighing(pairs) -> list:
    """``pairs`` ((training runs, run), ...), or none (equal weights) if a fit is too small."""
    return list(pairs) if all(len(train) >= MIN_WEIGHING_RUNS for train, _ in pairs) else []


def _weights(pairs, members, curves, measured, weighting) -> tuple[float, ...]:
    """The weights fitted on the held-out runs ``pairs`` ((training runs, run), ...), each
    run predicted by the members fitted on its training runs; none: equal weights."""
    if not pairs:
        return tuple(np.full(len(members), 1.0 / len(members)))
    predictions = [np.column_stack([curves[train][(m, run)].ravel() for m in members])
                   for train, run in pairs]  # fmt: skip
    target = [measured[run].ravel() for _, run in pairs]
    return tuple(float(w) for w in WEIGHTINGS[weighting](predictions, target))


def combine(
    runs, folds, members, curves, measured, weighting="rmse"
) -> tuple[Combination, dict[str, dict]]:
    """The super learner of ``members`` in every outer fold, and on all runs, weighted by
    ``weighting`` (a key of :data:`WEIGHTINGS`).

    ``curves`` maps each training set's runs to :func:`training_set_scores`' curves,
    ``measured`` each run to its error curves. An outer fold's weights are fitted on its
    inner predictions alone (each training run predicted by the members fitted on the other
    training runs: the held-out run reaches no weight); its held-out error is its members
    fitted on the training runs, so weighted. The final weights are fitted on every run's
    held-out predictions. Predictions of fits on fewer than :data:`MIN_WEIGHING_RUNS` runs
    weigh nothing: such a fold (three runs or two in all), or the final weights (two runs),
    weight the members equally. Returns the weights and each held-out run's error metrics.
    """
    members = tuple(members)
    by_run, errors, every, equal = {}, {}, [], []
    for fold in folds:
        held, train, splits = _outer_splits(runs, fold)
        inner = _weighing([(tuple(r for r in train if r != run), run) for (run,) in splits])
        weights = _weights(inner, members, curves, measured, weighting)
        for run in held:
            by_run[run] = weights
            if not inner:
                equal.append(run)
            outer = np.stack([curves[tuple(train)][(m, run)] for m in members], axis=-1)
            metrics = prediction_metrics(measured[run], outer @ np.asarray(weights))
            errors[run] = {name: float(metrics[name]) for name in METRIC_COLUMNS}
            every.append((tuple(train), run))
    every = _weighing(every)
    final = _weights(every, members, curves, measured, weighting)
    return Combination(members, by_run, final, tuple(equal), bool(every)), errors


def fold_scores(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    candidates: Sequence[Candidate],
    folds: Sequence[str | Sequence[str]],
    degree: int,
    signals: Sequence[str] = (),
    progress: Callable[[str], None] | None = None,
    map_sets: Callable[[Callable, list], list] | None = None,
    members: Sequence[str] = (),
    weighting: str = "rmse",
) -> tuple[list[pd.DataFrame], Combination | None]:
    """The rows of each outer fold (:func:`outer_fold_scores`), each training set fitted
    once, and the super learner of ``members`` (:func:`combine`; None without members),
    weighted by ``weighting`` (:data:`WEIGHTINGS`), whose held-out errors join each fold's
    rows as candidate :data:`COMBINED`.

    ``map_sets(function, training_sets)`` runs the training sets (default: in turn; the
    workflow spreads them over its cores, :func:`thermaxis.pipeline.parallel.map_folds`).
    """
    runs = natural_sorted(pd.unique(X["run"]).tolist())
    if len(runs) < 2:
        raise ValueError(f"{len(runs)} run: leave-one-condition-out needs at least 2")
    sets = training_sets(runs, folds)
    one_set = partial(
        training_set_scores, X, Y, candidates, degree=degree, signals=signals,
        progress=progress, members=tuple(members),
    )  # fmt: skip
    done = (map_sets or (lambda f, items: [f(i) for i in items]))(one_set, sets)
    scores = {s.train: d[0] for s, d in zip(sets, done, strict=True)}
    frames = [outer_fold_scores(runs, candidates, fold, scores) for fold in folds]
    if not members:
        return frames, None
    measured = {r: Y.loc[(X["run"] == r).to_numpy()].to_numpy(dtype=float) for r in runs}
    curves = {s.train: d[1] for s, d in zip(sets, done, strict=True)}
    combination, errors = combine(runs, folds, members, curves, measured, weighting)
    for i, fold in enumerate(folds):
        rows = [{"kind": "loco", "fold": run, "candidate": COMBINED, "held_out": run,
                 **errors[run]} for run in held_out_runs(fold)]  # fmt: skip
        frames[i] = pd.concat([frames[i], pd.DataFrame(rows, columns=SCORE_COLUMNS)],
                              ignore_index=True)  # fmt: skip
    return frames, combination


def _check_choice(names: Sequence[str], reference: str, members: Sequence[str]) -> None:
    if len(set(names)) != len(names):
        raise ValueError(f"candidate names must be unique, got {list(names)}")
    if reference not in names:
        raise ValueError(f"reference candidate {reference!r} is not one of {list(names)}")
    unknown = [m for m in members if m not in names]
    if unknown or not members:
        raise ValueError(
            f"config recommend.combine: {unknown[0] if unknown else 'empty'!r} is not a "
            f"candidate; expected names among {', '.join(names)}"
        )


def collect(
    scores: pd.DataFrame, names: Sequence[str], reference: str, combination: Combination
) -> Recommendation:
    """Every outer fold's combination and its held-out error, from the folds' scores."""
    _check_choice(names, reference, combination.members)
    combined = scores.loc[(scores["candidate"] == COMBINED) & (scores["kind"] == "loco")]
    scores = scores.loc[scores["candidate"].isin(names)]
    loco = scores.loc[
        scores["kind"] == "loco", ["candidate", "held_out", *METRIC_COLUMNS]
    ].reset_index(drop=True)
    inner = scores.loc[
        scores["kind"] == "inner", ["fold", "candidate", "held_out", *METRIC_COLUMNS]
    ]
    at = loco.set_index(["candidate", "held_out"])
    held = combined.set_index("held_out")
    rows = []
    for fold in natural_sorted(pd.unique(scores["fold"]).tolist()):
        weights = dict(zip(combination.members, combination.folds[fold], strict=True))
        rows.append(
            {
                "fold": fold,
                "chosen": COMBINED,
                **{f"weight_{m}": w for m, w in weights.items()},
                "rmse_um": held.loc[fold, "rmse"],
                "max_abs_um": held.loc[fold, "max_abs"],
                "paper_rmse_um": at.loc[(reference, fold), "rmse"],
                "paper_max_abs_um": at.loc[(reference, fold), "max_abs"],
            }
        )
    return Recommendation(
        pd.DataFrame(rows), inner.reset_index(drop=True), loco, COMBINED, combination
    )


def recommend(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    candidates: Sequence[Candidate],
    reference: str,
    degree: int,
    members: Sequence[str],
    max_loco_runs: int,
    n_group_folds: int,
    signals: Sequence[str] = (),
    outer_folds: Sequence[str] | None = None,
    progress: Callable[[str], None] | None = None,
    weighting: str = "rmse",
) -> Recommendation:
    """The nested leave-one-condition-out super learner of ``members`` among ``candidates``.

    ``reference`` names the candidate reported beside it (the paper's configuration).
    ``outer_folds`` default to every run, each held out alone up to ``max_loco_runs`` runs
    and in ``n_group_folds`` groups above. The workflow runs :func:`fold_scores` in one
    job, its training sets spread over the job's cores, and :func:`collect` once.
    """
    folds = (
        list(outer_folds)
        if outer_folds is not None
        else natural_sorted(pd.unique(X["run"]).tolist())
    )
    names = [c.name for c in candidates]
    _check_choice(names, reference, members)
    outer = run_groups(folds, max_loco_runs, n_group_folds)
    frames, combination = fold_scores(
        X, Y, candidates, outer, degree, signals, progress, members=members, weighting=weighting
    )
    return collect(pd.concat(frames, ignore_index=True), names, reference, combination)


def summary_of(recommendation: Recommendation) -> Mapping[str, float]:
    """Mean held-out errors of the nested choice and of the reference over the outer folds."""
    f = recommendation.folds
    return {
        "rmse_um": float(f["rmse_um"].mean()),
        "max_abs_um": float(f["max_abs_um"].mean()),
        "paper_rmse_um": float(f["paper_rmse_um"].mean()),
        "paper_max_abs_um": float(f["paper_max_abs_um"].mean()),
    }
