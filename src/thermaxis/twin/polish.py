"""The calibration's last leg: a compass search on the workflow's own faithfulness table.

The least-squares stages (:data:`thermaxis.twin.stages.STAGES`) see the pipeline through a
defect correction, and not its decoupled SVR: which (C, epsilon, gamma) the SVR's inner
search picks is a discrete choice, won by about 1 % on fold E4, so the held-out SVR's
error is a step function of the twin's parameters that finite differences cannot follow
(docs/datasets.md).  This leg reads the finished table instead: every candidate's raw
files are written and run through the pipeline as the workflow runs the paper's fold,
SVR included, and judged by :func:`thermaxis.paper.faithfulness.faithfulness`
(``evaluate``, passed in: :func:`thermaxis.twin.calibration.faithfulness_of`).

Compass search (a derivative-free pattern search, Kolda, Lewis & Torczon 2003): from the
current parameters, each free parameter alone is moved by plus and minus a fraction of
its physical range (:data:`STEPS`), rounded as ``twin_params.json`` stores it so that the
written file regenerates exactly the data judged here.  Candidates are ranked by

1. the number of targets that fail;
2. the summed shortfall of the failing targets, in units of their tolerances;
3. the smallest margin among the targets that failed where the leg started (larger first);

and the first in parameter order wins a tie.  The best candidate is taken when it ranks
above the current parameters; otherwise the step shrinks to the next of :data:`STEPS`.
The leg stops as soon as every target holds, and after :data:`MAX_SWEEPS` sweeps at most,
which bounds its cost (one sweep: two pipeline runs per free parameter).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import pandas as pd

from . import model as mdl
from .solver import worker_pool

__all__ = ["STEPS", "MAX_SWEEPS", "rank", "polish"]

#: Compass steps, as fractions of each parameter's physical range, largest first.
STEPS: tuple[float, ...] = (0.02, 0.01)
#: Sweeps at most over all steps (one sweep: every parameter up and down once).
MAX_SWEEPS = 2


def rank(table: pd.DataFrame, repaired: frozenset[str]) -> tuple[int, float, float]:
    """The sort key of a faithfulness table with margins: smaller is better.

    ``repaired``: the targets that failed where the leg started.
    """
    failing = table["holds"] == "no"
    margin = table.set_index("target")["margin"]
    shortfall = -float(table.loc[failing, "margin"].sum())
    worst_repaired = min((float(margin[t]) for t in repaired), default=0.0)
    return int(failing.sum()), round(shortfall, 12), -round(worst_repaired, 12)


def _candidates(
    x: np.ndarray, step: float, lower: np.ndarray, upper: np.ndarray
) -> list[tuple[int, float, np.ndarray]]:
    """Each parameter alone moved by -step and +step of its range, as the file rounds it."""
    out = []
    for i in range(x.size):
        for sign in (-1.0, 1.0):
            y = x.copy()
            y[i] = round(float(np.clip(x[i] + sign * step * (upper[i] - lower[i]),
                                       lower[i], upper[i])), mdl.PARAMS_DECIMALS)  # fmt: skip
            if y[i] != x[i]:
                out.append((i, sign, y))
    return out


def polish(
    params: mdl.TwinParams,
    evaluate: Callable[[mdl.TwinParams], pd.DataFrame],
    workers: int = 2,
) -> tuple[mdl.TwinParams, dict]:
    """The compass search from ``params``: the parameters it ends at, and its record.

    ``evaluate(params)`` is the faithfulness table (with margins) of ``params``'s raw files.
    Deterministic on any number of ``workers``: candidates are judged in a fixed order.
    """
    start = time.perf_counter()
    runs = tuple(sorted(params.initial))
    lower, upper = mdl.parameter_bounds(runs)
    x = np.round(params.vector(runs), mdl.PARAMS_DECIMALS)
    table = evaluate(mdl.TwinParams.from_vector(x, runs))
    repaired = frozenset(table.loc[table["holds"] == "no", "target"])
    current = rank(table, repaired)
    moves, evaluations, sweeps, steps = [], 1, 0, list(STEPS)
    pool = worker_pool(workers)
    try:
        while current[0] and steps and sweeps < MAX_SWEEPS:
            candidates = _candidates(x, steps[0], lower, upper)
            trial = [mdl.TwinParams.from_vector(y, runs) for _, _, y in candidates]
            tables = pool.map(evaluate, trial) if pool else list(map(evaluate, trial))
            evaluations += len(trial)
            sweeps += 1
            best, key = _best_candidate(tables, repaired)
            if key < current:
                i, sign, x = candidates[best]
                current = key
                moves.append(f"{mdl.parameter_names(runs)[i]} {sign * steps[0]:+g} of its range")
            else:
                steps.pop(0)
    finally:
        if pool is not None:
            pool.close()
            pool.join()
    record = dict(
        name="polish",
        moves=moves,
        failing=current[0],
        evaluations=evaluations,
        seconds=round(time.perf_counter() - start, 1),
    )
    return mdl.TwinParams.from_vector(x, runs), record


def _best_candidate(tables: list[pd.DataFrame], repaired: frozenset) -> tuple[int, tuple]:
    """The candidate whose faithfulness table ranks first, and its rank; ties to the first."""
    keys = [rank(t, repaired) for t in tables]
    best = min(range(len(keys)), key=keys.__getitem__)
    return best, keys[best]
