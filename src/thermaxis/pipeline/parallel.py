"""The folds of one job spread over its cores, with the warnings of a single process.

A stage job runs every fold (the models, the recommendation); each fold is independent
of the others and deterministic, so running them in worker processes changes nothing but
the time. The workers are fresh interpreters (joblib's loky backend, not a fork of a
process whose BLAS and OpenMP threads are running), and every warning a worker raises
is raised again in the job's own process, in fold order, so that its log and the
terminal see what one process would have shown.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence

__all__ = ["FOLDS_PER_WORKER", "map_folds", "fold_workers"]

# Below this many folds a worker's start (a new interpreter importing the library, about
# 1.5 s) costs more than the folds it would take over: a fold of the models job fits each
# configuration once (tenths of a second), a fold of the recommendation runs every
# candidate's inner loop (seconds: 3.9 s on the twin), a run of the clean job is read and
# cleaned in 0.2-0.4 s (the twin, fl_thermal).
FOLDS_PER_WORKER = {"models": 4, "recommend": 1, "clean": 8}


def fold_workers(cores: int, n_folds: int, stage: str) -> int:
    """How many processes the ``stage`` job (:data:`FOLDS_PER_WORKER`) with ``n_folds``
    folds uses on ``cores`` cores."""
    return max(1, min(int(cores), n_folds // FOLDS_PER_WORKER[stage]))


def _recorded(function: Callable, item):
    from threadpoolctl import threadpool_limits

    # One BLAS/OpenMP thread per worker: the workers are the parallelism, and BLAS
    # threads spinning beside them on the same cores only burn CPU time.
    with threadpool_limits(limits=1), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        value = function(item)
    return value, [(str(w.message), w.category, w.filename, w.lineno) for w in caught]


def map_folds(function: Callable, items: Sequence, workers: int) -> list:
    """``[function(item) for item in items]``, in ``workers`` processes when more than one.

    ``function`` must be picklable (a module-level function, or a ``functools.partial`` of
    one); an exception in a worker is raised here.
    """
    if workers <= 1 or len(items) <= 1:
        return [function(item) for item in items]
    from joblib import Parallel, delayed

    done = Parallel(n_jobs=workers, backend="loky")(
        delayed(_recorded)(function, item) for item in items
    )
    values = []
    for value, caught in done:
        for message, category, filename, lineno in caught:
            warnings.warn_explicit(message, category, filename, lineno)
        values.append(value)
    return values
