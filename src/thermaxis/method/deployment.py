"""What the compensation deploys of the recommendation: the paper's model, one candidate or
the super learner, and the setup (columns, selection, settings) it is fitted with."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import pandas as pd

from thermaxis.config import ModelSettings, SelectionSettings
from thermaxis.method.candidates import candidate_from_record, candidate_view

__all__ = [
    "deployed_record",
    "DeployedSetup",
    "deployed_setup",
]


def deployed_record(model: str, choice: Mapping, fold: str | None = None) -> dict | None:
    """What the compensation deploys (on ``fold``'s training runs when given).

    ``model`` is config ``compensation.model``: ``paper`` (None: the configured approach
    and algorithm), ``recommended`` (the super learner: ``{"name", "members": [(candidate
    record, weight), ...]}`` with the final weights, or those of ``fold``) or a candidate's
    name (one member of weight 1). Every candidate can be deployed: ``model.json``,
    :class:`~thermaxis.compensation.runtime.Compensator` and the Structured Text block
    read temperatures, operating signals and their lags cycle by cycle.
    """
    if model == "paper":
        return None
    if model == "recommended":
        weights = choice["final"]["weights"] if fold is None else choice["folds"][fold]
        return {
            "name": choice["final"]["name"],
            "members": [(choice["candidates"][m], float(w)) for m, w in weights.items()],
        }
    if model in choice["candidates"]:
        return {"name": model, "members": [(choice["candidates"][model], 1.0)]}
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
