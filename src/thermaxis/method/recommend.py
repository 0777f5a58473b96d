"""Which model a user's own runs support: a nested leave-one-condition-out choice.

A *candidate* is one configuration the main workflow or the sweep can express: an
approach, an algorithm, a sensitive-point selection and the inputs it may use
(temperatures, their time-aware lags, the operating signals). The question a machine
builder asks is which candidate to deploy and how much error it leaves on a condition
it has not seen. Answering it honestly needs two loops:

* the *outer* loop holds out one condition (run) at a time: it is the unseen condition;
* the *inner* loop, on the remaining training runs alone, scores every candidate by
  leave-one-condition-out, one run at a time whatever the number of runs, and chooses
  the candidate with the lowest mean inner score (:func:`_choose`: the cross-validation
  selector, or discrete super learner, of van der Laan, Polley and Hubbard 2007), ties
  to the candidate listed first (the default list runs from simple to complex).

The chosen candidate's error on the outer held-out run is the estimate of what the
pipeline would deploy; the held-out run reaches no choice. The final recommendation is
the same choice made on all runs, whose scores are the candidates' own
leave-one-condition-out errors.

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

from thermaxis.config import (
    ModelSettings,
    RecommendSettings,
    SelectionSettings,
    selection_overrides,
)
from thermaxis.labels import natural_sorted
from thermaxis.method.batched import batchable, decoupled_metrics, pointwise_metrics
from thermaxis.method.folds import (
    META,
    fit_held_out,
    fold_metrics,
    fold_name,
    held_out_runs,
    run_groups,
    select_for_fold,
)
from thermaxis.method.inputs import base_of, parse_input_name
from thermaxis.reports.formatting import markdown_table

__all__ = [
    "SCORES",
    "Candidate",
    "Recommendation",
    "candidate_view",
    "held_out_scores",
    "held_out_predictions",
    "SCORE_COLUMNS",
    "TrainingSet",
    "training_sets",
    "training_set_scores",
    "outer_fold_scores",
    "fold_scores",
    "collect",
    "recommend",
    "default_candidates",
    "BASELINE",
    "EVIDENCE",
    "baseline_candidate",
    "evidence_candidate",
    "extra_candidates",
    "candidate_table",
    "candidates_for",
    "configured_candidates",
    "candidate_record",
    "candidate_from_record",
    "recommendation_markdown",
    "summary_of",
    "deployed_record",
    "DeployedSetup",
    "deployed_setup",
    "held_out_accuracy",
]

# What the inner loop minimises: the mean over inner folds of the held-out error curves'
# largest |residual| (what a compensation must bound) or their RMSE.
SCORES = ("max_abs", "rmse")
# Every held-out score recorded (model.json's held_out_accuracy takes them all).
METRICS = ("rmse", "max_abs", "mae", "residual_min", "residual_max")


@dataclass(frozen=True)
class Candidate:
    """One configuration the recommendation may choose.

    ``time_inputs`` lets the candidate's selection and model see the time-aware input
    columns of X (their names hold ``@``, e.g. ``T5@lag30min``) whose lag time constants
    are ``lags_min``; without it they are dropped. ``models.signals`` are the operating
    signals it uses as inputs.
    """

    name: str
    approach: str
    algorithm: str
    selection: SelectionSettings
    models: ModelSettings
    time_inputs: bool
    lags_min: tuple[float, ...] = ()


@dataclass(frozen=True)
class Recommendation:
    """The outcome: per outer fold the choice and its honest error, and the final choice.

    ``folds`` has one row per outer fold: fold, chosen, inner_score (the chosen
    candidate's mean inner score), rmse_um, max_abs_um (the chosen candidate on the
    held-out run), paper_rmse_um, paper_max_abs_um (the reference candidate there).
    ``inner`` has one row per outer fold x candidate x inner held-out run.
    ``loco`` has one row per candidate x run: each candidate's leave-one-condition-out
    error on all runs, whose means choose ``final``.
    """

    folds: pd.DataFrame
    inner: pd.DataFrame
    loco: pd.DataFrame
    final: str
    score: str


def candidate_view(X: pd.DataFrame, candidate: Candidate, signals: Sequence[str]):
    """What a candidate may use: (X's columns it sees, those selection may choose, its settings).

    Temperatures, and with ``time_inputs`` their lags, are candidates for the sensitive
    points; the operating signals the candidate uses (and their lags) are added to every
    model's inputs, as ``models.signals`` does, never selected.
    """
    every_derived = [c for c in X.columns if "@" in str(c)]
    temperatures = [
        c for c in X.columns if c not in META and c not in signals and c not in every_derived
    ]
    derived = [c for c in every_derived if _seen_lag(c, candidate.lags_min)]
    if candidate.time_inputs:
        temperatures += [c for c in derived if base_of(c) not in signals]
    used = [s for s in candidate.models.signals if s in X.columns]
    if candidate.time_inputs:
        used += [c for c in derived if base_of(c) in candidate.models.signals]
    keys = [c for c in X.columns if c in META]
    return (
        X[keys + temperatures + used],
        keys + temperatures,
        replace(candidate.models, signals=tuple(used)),
    )


def _seen_lag(name: str, lags_min: Sequence[float]) -> bool:
    """Whether derived input ``name`` is a lag at one of the time constants ``lags_min``."""
    _, kind, seconds = parse_input_name(name)
    return kind == "lag" and any(np.isclose(seconds, 60.0 * m) for m in lags_min)


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


def _error_metrics(X, Y, fold, candidate, degree, signals, cache) -> list[tuple]:
    """Select on the training rows of X, fit, predict ``fold``: its error metrics.

    ``fold`` is a run or a group of runs, fitted once: ``[(run, metrics), ...]`` for each
    of its runs.
    """
    view, models, selection = _fold_setup(X, Y, fold, candidate, degree, signals, cache)
    decoupled = candidate.approach == "decoupled"
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
        (row["fold"], {name: float(row[name]) for name in METRICS}) for _, row in errors.iterrows()
    ]


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
    decoupled = candidate.approach == "decoupled"
    estimator, X_test, _ = fit_held_out(
        view, Y, fold, candidate.approach, candidate.algorithm, selection, models,
        degree if decoupled else None,
    )  # fmt: skip
    predicted = estimator.predict(X_test)
    return X_test["run"].to_numpy(), np.asarray(predicted, dtype=float)


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
        for name, metrics in _error_metrics(X, Y, group, candidate, degree, signals, cache):
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
) -> dict[tuple[str, str], dict]:
    """Every candidate fitted once on ``training.train``, scored on each held-out run.

    ``{(candidate, run): metrics}``: the held-out runs share one call (they are all held
    out of the same fit).
    """
    say = progress or (lambda message: None)
    cache: dict = {}
    out = {}
    for candidate in candidates:
        say(f"training runs {fold_name(training.train)}: {candidate.name}")
        for row in held_out_scores(
            X, Y, [*training.train, *training.scored], [training.scored], candidate, degree,
            signals, cache,
        ):  # fmt: skip
            out[(candidate.name, row["held_out"])] = {m: row[m] for m in METRICS}
    return out


SCORE_COLUMNS = ["kind", "fold", "candidate", "held_out", *METRICS]


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


def fold_scores(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    candidates: Sequence[Candidate],
    folds: Sequence[str | Sequence[str]],
    degree: int,
    signals: Sequence[str] = (),
    progress: Callable[[str], None] | None = None,
    map_sets: Callable[[Callable, list], list] | None = None,
) -> list[pd.DataFrame]:
    """The rows of each outer fold (:func:`outer_fold_scores`), each training set fitted once.

    ``map_sets(function, training_sets)`` runs the training sets (default: in turn; the
    workflow spreads them over its cores, :func:`thermaxis.pipeline.parallel.map_folds`).
    """
    runs = natural_sorted(pd.unique(X["run"]).tolist())
    if len(runs) < 2:
        raise ValueError(f"{len(runs)} run: leave-one-condition-out needs at least 2")
    sets = training_sets(runs, folds)
    one_set = partial(
        training_set_scores, X, Y, candidates, degree=degree, signals=signals, progress=progress
    )
    done = (map_sets or (lambda f, items: [f(i) for i in items]))(one_set, sets)
    scores = {s.train: d for s, d in zip(sets, done, strict=True)}
    return [outer_fold_scores(runs, candidates, fold, scores) for fold in folds]


def _lowest(means: pd.Series, order: Sequence[str]) -> str:
    """The lowest mean; ties (to 1e-12 relative) go to the first listed."""
    best = min(means.loc[list(order)])
    return next(n for n in order if np.isclose(means[n], best, rtol=1e-12, atol=0.0))


def _choose(scores: pd.DataFrame, order: Sequence[str], score: str) -> tuple[str, float]:
    """The candidate with the lowest mean held-out score over the held-out runs.

    The cross-validation selector (the discrete super learner of van der Laan, Polley and
    Hubbard 2007): with every held-out run a piece of evidence, its risk is within a
    constant of the best candidate's as the runs grow, for a fixed, small list of
    candidates; so the list is kept short and structurally different
    (:func:`default_candidates`). Ties (to 1e-12 relative) go to the candidate listed
    first, the simpler one.
    """
    wide = scores.pivot_table(index="held_out", columns="candidate", values=score, sort=True)
    name = _lowest(wide.mean(), order)
    return name, float(wide.mean()[name])


def _check_choice(names: Sequence[str], reference: str, score: str) -> None:
    if score not in SCORES:
        raise ValueError(f"config recommend.score: {score!r} is not one of {', '.join(SCORES)}")
    if len(set(names)) != len(names):
        raise ValueError(f"candidate names must be unique, got {list(names)}")
    if reference not in names:
        raise ValueError(f"reference candidate {reference!r} is not one of {list(names)}")


def collect(
    scores: pd.DataFrame, names: Sequence[str], reference: str, score: str
) -> Recommendation:
    """The choice of every outer fold, and the final one, from the folds' scores."""
    _check_choice(names, reference, score)
    scores = scores.loc[scores["candidate"].isin(names)]
    loco = scores.loc[scores["kind"] == "loco", ["candidate", "held_out", *METRICS]].reset_index(
        drop=True
    )
    inner = scores.loc[scores["kind"] == "inner", ["fold", "candidate", "held_out", *METRICS]]
    at = loco.set_index(["candidate", "held_out"])
    rows = []
    for fold in natural_sorted(pd.unique(scores["fold"]).tolist()):
        fold_inner = inner.loc[inner["fold"] == fold]
        # No inner scores (one training run): the reference stands, unchosen.
        chosen, inner_score = (
            _choose(fold_inner, names, score) if len(fold_inner) else (reference, np.nan)
        )
        rows.append(
            {
                "fold": fold,
                "chosen": chosen,
                "inner_score": inner_score,
                "rmse_um": at.loc[(chosen, fold), "rmse"],
                "max_abs_um": at.loc[(chosen, fold), "max_abs"],
                "paper_rmse_um": at.loc[(reference, fold), "rmse"],
                "paper_max_abs_um": at.loc[(reference, fold), "max_abs"],
            }
        )
    final, _ = _choose(loco, names, score)
    return Recommendation(pd.DataFrame(rows), inner.reset_index(drop=True), loco, final, score)


def recommend(
    X: pd.DataFrame,
    Y: pd.DataFrame,
    candidates: Sequence[Candidate],
    reference: str,
    degree: int,
    score: str,
    max_loco_runs: int,
    n_group_folds: int,
    signals: Sequence[str] = (),
    outer_folds: Sequence[str] | None = None,
    progress: Callable[[str], None] | None = None,
) -> Recommendation:
    """Nested leave-one-condition-out choice among ``candidates`` (simplest first).

    ``reference`` names the candidate reported beside the choice (the paper's
    configuration). ``outer_folds`` default to every run, each held out alone up to
    ``max_loco_runs`` runs and in ``n_group_folds`` groups above. The workflow runs
    :func:`fold_scores` in one job, its training sets spread over the job's cores, and
    :func:`collect` once.
    """
    folds = (
        list(outer_folds)
        if outer_folds is not None
        else natural_sorted(pd.unique(X["run"]).tolist())
    )
    names = [c.name for c in candidates]
    _check_choice(names, reference, score)
    outer = run_groups(folds, max_loco_runs, n_group_folds)
    scores = pd.concat(
        fold_scores(X, Y, candidates, outer, degree, signals, progress), ignore_index=True
    )
    return collect(scores, names, reference, score)


def candidate_table(candidates: Sequence[Candidate]) -> pd.DataFrame:
    """One row per candidate: what it is, in words a reader of the table needs."""
    return pd.DataFrame(
        [
            {
                "candidate": c.name,
                "approach": c.approach,
                "algorithm": c.algorithm,
                "selection": c.selection.method,
                "n_clusters": c.selection.n_clusters
                if c.selection.method in ("fuzzy_grey", "correlation")
                else np.nan,
                "time_inputs": c.time_inputs,
                "signals": " ".join(c.models.signals),
            }
            for c in candidates
        ]
    )


def summary_of(recommendation: Recommendation) -> Mapping[str, float]:
    """Mean held-out errors of the nested choice and of the reference over the outer folds."""
    f = recommendation.folds
    return {
        "rmse_um": float(f["rmse_um"].mean()),
        "max_abs_um": float(f["max_abs_um"].mean()),
        "paper_rmse_um": float(f["paper_rmse_um"].mean()),
        "paper_max_abs_um": float(f["paper_max_abs_um"].mean()),
    }


BASELINE = "baseline-ridge+lags"
EVIDENCE = "evidence-ridge"


def baseline_candidate(
    selection: SelectionSettings, models: ModelSettings, lags_min: Sequence[float]
) -> Candidate:
    """The strong plain baseline (:data:`BASELINE`): what a user would fit in a notebook.

    A ridge per target (point by point), over every sensor's rise and its causal
    first-order lags at ``lags_min`` (config ``recommend.baseline_lags_min``), the strength
    chosen by inner leave-one-condition-out on the training runs; no operating signal.
    """
    return Candidate(
        BASELINE,
        "pointwise",
        "ridge",
        replace(selection, method="all"),
        replace(models, signals=(), searched=("ridge",)),
        True,
        tuple(lags_min),
    )


def evidence_candidate(
    selection: SelectionSettings,
    models: ModelSettings,
    decoupled: bool,
    signals: Sequence[str],
    lags_min: Sequence[float] = (),
) -> Candidate:
    """The evidence ridge (:data:`EVIDENCE`, with ``lags_min`` ``+lags``): the other plain reference.

    scikit-learn's BayesianRidge (algorithm ``bayesridge``) on standardised inputs, over
    every sensor, with the declared operating ``signals`` as inputs; decoupled where there
    are several positions (k on absolute temperatures, b on their rise, Eq. 9), point by
    point otherwise. Its strength maximises the evidence of the training rows, so it needs
    no inner search and spends no run on one.
    """
    return Candidate(
        EVIDENCE + ("+lags" if lags_min else ""),
        "decoupled" if decoupled else "pointwise",
        "bayesridge",
        replace(selection, method="all"),
        replace(models, signals=tuple(signals), searched=()),
        bool(lags_min),
        tuple(lags_min),
    )


def default_candidates(
    selection: SelectionSettings,
    models: ModelSettings,
    decoupled: bool,
    signals: Sequence[str],
    lags_min: Sequence[float],
    baseline_lags_min: Sequence[float],
    kernel: bool = True,
) -> list[Candidate]:
    """A short list of structurally different candidates, simplest first.

    * ``paper``: the configured selection, the decoupled approach (point by point for a
      single-position dataset) and MLR, as the paper models (also the reference);
    * the evidence ridge over every sensor (:func:`evidence_candidate`), without and with
      the lags ``baseline_lags_min``;
    * the plain baseline (:func:`baseline_candidate`): ridge over every sensor's rise and
      its lags ``baseline_lags_min``, its strength searched;
    * PLS over every sensor with the operating signals, its components searched, and with
      ``lags_min`` again with those lags;
    * with ``kernel``, the point-by-point SVR on the configured selection (a kernel model's
      inner search is costly: config ``recommend.kernel_max_runs`` caps it).

    Each is a different kind of model (selected points, shrinkage by the evidence or by a
    search, latent components, a kernel): the choice among a few such candidates is
    what the runs can support; twenty near-duplicates made it noise.
    """
    first = "decoupled" if decoupled else "pointwise"
    every_sensor = replace(selection, method="all")
    pls = Candidate(
        f"{first}-pls-all",
        first,
        "pls",
        every_sensor,
        replace(models, signals=tuple(signals), searched=("pls",)),
        False,
    )
    candidates = [
        Candidate(
            "paper", first, "mlr", selection, replace(models, signals=(), searched=()), False
        ),
        evidence_candidate(selection, models, decoupled, signals),
        evidence_candidate(selection, models, decoupled, signals, baseline_lags_min),
        baseline_candidate(selection, models, baseline_lags_min),
        pls,
    ]
    if lags_min:
        candidates.append(
            replace(pls, name=f"{pls.name}+lags", time_inputs=True, lags_min=tuple(lags_min))
        )
    if kernel:
        candidates.append(
            Candidate(
                "pointwise-svr",
                "pointwise",
                "svr",
                selection,
                replace(models, signals=(), searched=()),
                False,
            )  # fmt: skip
        )
    return candidates


def extra_candidates(
    settings, selection: SelectionSettings, models: ModelSettings, signals: Sequence[str]
):
    """The user's candidates (config ``recommend.extra_candidates``), after the default ones."""
    out = []
    for extra in settings.extra_candidates:
        used = tuple(signals) if extra.signals else ()
        out.append(
            Candidate(
                name=extra.name,
                approach=extra.approach,
                algorithm=extra.algorithm,
                selection=selection_overrides(selection, dict(extra.selection)),
                models=replace(models, signals=used, searched=("ridge", "lasso", "pls")),
                time_inputs=extra.time_inputs,
                lags_min=tuple(settings.lags_min) if extra.time_inputs else (),
            )
        )
    return out


def candidates_for(
    selection: SelectionSettings,
    models: ModelSettings,
    recommend_settings,
    decoupled: bool,
    signals: Sequence[str],
    n_runs: int,
) -> list[Candidate]:
    """The configured candidate list: the defaults, then the user's (config ``recommend``).

    The kernel candidate is in the list only up to ``recommend.kernel_max_runs`` runs: its
    search is a kernel fit per grid point and inner run, nested twice.
    """
    return [
        *default_candidates(
            selection,
            models,
            decoupled,
            signals,
            recommend_settings.lags_min,
            recommend_settings.baseline_lags_min,
            kernel=n_runs <= recommend_settings.kernel_max_runs,
        ),
        *extra_candidates(recommend_settings, selection, models, signals),
    ]


def configured_candidates(params) -> list[Candidate]:
    """The candidate list of the recommendation rules, from their params (config sections)."""
    return candidates_for(
        SelectionSettings.from_section(params.selection),
        ModelSettings.from_section(params.models),
        RecommendSettings.from_section(params.recommend),
        params.decoupled,
        params.signals,
        len(params.folds),
    )


def candidate_record(candidate: Candidate) -> dict:
    """A candidate as plain JSON: what the compensation refits on all runs."""
    selection = {
        f: getattr(candidate.selection, f) for f in candidate.selection.__dataclass_fields__
    }
    selection["fixed"] = {target: list(sensors) for target, sensors in candidate.selection.fixed}
    return {
        "name": candidate.name,
        "approach": candidate.approach,
        "algorithm": candidate.algorithm,
        "selection": selection,
        "signals": list(candidate.models.signals),
        "searched": list(candidate.models.searched),
        "time_inputs": candidate.time_inputs,
        "lags_min": list(candidate.lags_min),
    }


def candidate_from_record(record: Mapping, models: ModelSettings) -> Candidate:
    """The inverse of :func:`candidate_record`, on the configured model settings."""
    selection = SelectionSettings.from_section(record["selection"])
    return Candidate(
        name=record["name"],
        approach=record["approach"],
        algorithm=record["algorithm"],
        selection=selection,
        models=replace(
            models, signals=tuple(record["signals"]), searched=tuple(record["searched"])
        ),
        time_inputs=bool(record["time_inputs"]),
        lags_min=tuple(float(m) for m in record["lags_min"]),
    )


def recommendation_markdown(recommendation: Recommendation, statement: str) -> str:
    """recommendation.md: the answer first, then the folds."""
    s = summary_of(recommendation)
    f = recommendation.folds
    head = (
        f"# Recommended model\n\n{statement}\n\n"
        f"Recommended (chosen on all runs): **{recommendation.final}**. Chosen fold by fold without the "
        f"held-out run (score: mean inner {recommendation.score}), the pipeline's choice leaves a mean "
        f"held-out RMSE of {s['rmse_um']:.2f} µm and a mean largest |residual| of {s['max_abs_um']:.2f} µm, "
        f"against {s['paper_rmse_um']:.2f} and {s['paper_max_abs_um']:.2f} µm for the paper's configuration "
        f"on the same folds.\n\n"
    )
    unchosen = f.loc[f["inner_score"].isna(), "fold"].astype(str).tolist()
    if unchosen:
        # One training run leaves nothing to hold out inside the fold (collect).
        head += (
            f"Fold(s) {', '.join(unchosen)} had a single training run, so no inner split to "
            "choose on: they keep the paper's configuration.\n\n"
        )
    return head + markdown_table(f, "%.3f")


def deployed_record(model: str, choice: Mapping, fold: str | None = None) -> dict | None:
    """The candidate record the compensation deploys (on ``fold``'s training runs when given).

    ``model`` is config ``compensation.model``: ``paper`` (None: the configured approach
    and algorithm), ``recommended`` (the final choice, or the one chosen without
    ``fold``) or a candidate's name. Every candidate can be deployed: ``model.json``,
    :class:`~thermaxis.compensation.runtime.Compensator` and the Structured Text block
    read temperatures, operating signals and their lags cycle by cycle.
    """
    if model == "paper":
        return None
    if model == "recommended":
        return choice["final"] if fold is None else choice["folds"][fold]
    if model in choice["candidates"]:
        return choice["candidates"][model]
    raise ValueError(
        f"config compensation.model: {model!r} is not 'recommended', 'paper' or a candidate "
        f"({', '.join(choice['candidates'])})"
    )


@dataclass(frozen=True)
class DeployedSetup:
    """What the compensation fits: the columns of X it sees, those its selection may
    choose, and its approach, selection, model and compensation settings."""

    view: pd.DataFrame
    selectable: list
    approach: str
    selection: SelectionSettings
    models: ModelSettings
    settings: object


def deployed_setup(
    record: Mapping | None,
    X: pd.DataFrame,
    approach: str,
    selection: SelectionSettings,
    models: ModelSettings,
    settings,
    signals: Sequence[str],
) -> DeployedSetup:
    """The deployed model's setup (:class:`DeployedSetup`).

    ``record`` is :func:`deployed_record`'s; None keeps the configured model (``approach``,
    ``selection``, ``models`` and ``settings.algorithm``) on the temperatures alone, as the
    paper models. A candidate sees what it saw in the recommendation (:func:`candidate_view`).
    """
    if record is None:
        keep = [c for c in X.columns if c not in signals and "@" not in str(c)]
        return DeployedSetup(X[keep], keep, approach, selection, models, settings)
    candidate = candidate_from_record(record, models)
    view, selectable, candidate_models = candidate_view(X, candidate, signals)
    return DeployedSetup(
        view,
        selectable,
        candidate.approach,
        candidate.selection,
        candidate_models,
        replace(settings, algorithm=candidate.algorithm),
    )


def held_out_accuracy(scores: pd.DataFrame, name: str) -> list[dict]:
    """A candidate's leave-one-condition-out errors as model.json's held_out_accuracy."""
    rows = scores.loc[(scores["kind"] == "loco") & (scores["candidate"] == name)]
    return [
        {"fold": str(r["held_out"]), "target": "error", **{m: float(r[m]) for m in METRICS}}
        for r in rows.to_dict("records")
    ]
