"""The recommendation's candidates: what each may use, the default list, and their JSON records.

A *candidate* is one configuration the main workflow or the sweep can express: an
approach, an algorithm, a sensitive-point selection and the inputs it may use
(temperatures, their time-aware lags, the operating signals). The nested evaluation that
scores and combines them is :mod:`thermaxis.method.nested`; what the compensation deploys
of them, :mod:`thermaxis.method.deployment`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from thermaxis.config import (
    KERNEL_CANDIDATE,
    ModelSettings,
    RecommendSettings,
    SelectionSettings,
    selection_overrides,
)
from thermaxis.method.folds import META
from thermaxis.method.inputs import base_of, parse_input_name

__all__ = [
    "Candidate",
    "candidate_view",
    "candidate_table",
    "BASELINE",
    "PAPER",
    "baseline_candidate",
    "evidence_candidate",
    "default_candidates",
    "extra_candidates",
    "candidates_for",
    "configured_candidates",
    "candidate_record",
    "candidate_from_record",
    "EVIDENCE",
]


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


PAPER = "paper"
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
    pls = _pls_candidate(first, selection, models, signals)
    candidates = [
        Candidate(PAPER, first, "mlr", selection, replace(models, signals=(), searched=()), False),
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
        candidates.append(_kernel_candidate(selection, models))
    return candidates


def _pls_candidate(
    approach: str, selection: SelectionSettings, models: ModelSettings, signals: Sequence[str]
) -> Candidate:
    """PLS over every sensor with the operating signals, its components searched."""
    return Candidate(
        f"{approach}-pls-all",
        approach,
        "pls",
        replace(selection, method="all"),
        replace(models, signals=tuple(signals), searched=("pls",)),
        False,
    )


def _kernel_candidate(selection: SelectionSettings, models: ModelSettings) -> Candidate:
    """The point-by-point SVR on the configured selection: the kernel candidate."""
    return Candidate(
        KERNEL_CANDIDATE,
        "pointwise",
        "svr",
        selection,
        replace(models, signals=(), searched=()),
        False,
    )


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
