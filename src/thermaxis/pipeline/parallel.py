"""The folds of one job spread over its cores, with the warnings of a single process.

A stage job runs every fold (the models, the recommendation); each fold is independent
of the others and deterministic, so running them in worker processes changes nothing but
the time. The workers are fresh interpreters (joblib's loky backend, not a fork of a
process whose BLAS and OpenMP threads are running), and every warning a worker raises
is raised again in the job's own process, in fold order, so that its log and the
terminal see what one process would have shown.

The job's own process takes folds too, from the front, while the workers start; a worker
takes folds from the back, one at a time, once it has imported the library. A worker's
start (about 1.5-2.5 s) then never delays a fold: on small data the job's process has
done every fold before a worker is ready, and on large data one process fewer is started.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable, Sequence

from thermaxis.errors import raise_again, recorded

__all__ = ["FOLDS_PER_WORKER", "map_folds", "fold_workers"]

# A second process pays only when there are folds to share: the job's own process does a
# fold while a worker starts (a new interpreter importing the library, about 1.5-2.5 s),
# and a job holding two cores keeps Snakemake from starting another job on the second.
# A fold of the models job fits each configuration once (tenths of a second); the
# recommendation's folds share their fits by training runs, so its processes take training
# sets, about 1 s each on the twin (10 of them for 4 folds), while its folds still set how
# many processes pay. The recommendation runs beside the models, figures and reports: a
# second process shortened the twin's job (4 folds) by 1 s and fl_thermal's (6) by 5 s but
# lengthened both runs, holding both cores while other jobs were ready. The models and the
# recommendation, ready together, change at the same fold count: a two-core job waits
# for both cores, so beside a one-core recommendation the models waited 126 s on a 12-run
# record, one core idle for 88 s (docs/performance.md). A run of the clean job is read and
# cleaned in 0.2-0.4 s (the twin, fl_thermal).
FOLDS_PER_WORKER = {"models": 4, "recommend": 4, "clean": 8}


def fold_workers(cores: int, n_folds: int, stage: str) -> int:
    """How many processes the ``stage`` job (:data:`FOLDS_PER_WORKER`) with ``n_folds``
    folds uses on ``cores`` cores."""
    return max(1, min(int(cores), n_folds // FOLDS_PER_WORKER[stage]))


def _recorded(function: Callable, item):
    from threadpoolctl import threadpool_limits

    # One BLAS/OpenMP thread per worker: the workers are the parallelism, and BLAS
    # threads spinning beside them on the same cores only burn CPU time.
    with threadpool_limits(limits=1):
        return recorded(function, item)


def _import(module: str) -> None:
    import importlib

    importlib.import_module(module)


def map_folds(function: Callable, items: Sequence, workers: int) -> list:
    """``[function(item) for item in items]``, shared with ``workers - 1`` worker
    processes when ``workers`` is more than one.

    ``function`` must be picklable (a module-level function, or a ``functools.partial`` of
    one). The exception of the first failing fold is raised here, as in one process.
    """
    if workers <= 1 or len(items) <= 1:
        return [function(item) for item in items]
    from joblib.externals.loky import get_reusable_executor

    folds = _Folds(function, items)
    executor = get_reusable_executor(max_workers=workers - 1)
    for _ in range(workers - 1):
        threading.Thread(target=folds.serve, args=(executor,), daemon=True).start()
    try:
        while (i := folds.take(from_back=False)) is not None:
            folds.run(i)
        with folds.settled:
            folds.settled.wait_for(lambda: folds.running == 0)
    finally:
        # A worker still importing the library is not waited for.
        executor.shutdown(wait=False, kill_workers=True)
    return folds.values()


class _Folds:
    """The folds of one :func:`map_folds` call, taken from the front by the job's own
    process and from the back by the threads serving the workers.

    One condition guards the queue and the outcomes, which every thread reads.
    """

    def __init__(self, function: Callable, items: Sequence) -> None:
        self.function, self.items = function, items
        self.pending = deque(range(len(items)))
        self.settled = threading.Condition()
        self.running = 0  # folds taken and not finished
        self.done: dict[int, tuple] = {}
        self.failed: dict[int, BaseException] = {}

    def take(self, from_back: bool) -> int | None:
        # After a failure only the folds before it still run, so the error raised is the
        # one a single process would have raised.
        with self.settled:
            pending, failed = self.pending, self.failed
            if not pending or (failed and pending[-1 if from_back else 0] > min(failed)):
                return None
            self.running += 1
            return pending.pop() if from_back else pending.popleft()

    def run(self, i: int, executor=None) -> None:
        outcome, value = self.done, None
        try:
            if executor is None:
                value = _recorded(self.function, self.items[i])
            else:
                value = executor.submit(_recorded, self.function, self.items[i]).result()
        except BaseException as exc:  # raised below, in the job's own process
            outcome, value = self.failed, exc
        finally:
            # Under the lock: take() reads `failed` from the other threads.
            with self.settled:
                outcome[i] = value
                self.running -= 1
                self.settled.notify_all()

    def serve(self, executor) -> None:
        # A fold handed to a worker that is still starting would wait there while the
        # job's process could have done it: a worker is handed folds once it is ready.
        # A worker that cannot start (or is stopped by map_folds) leaves its folds to this process.
        function = self.function
        try:
            executor.submit(_import, getattr(function, "func", function).__module__).result()
        except BaseException:
            return
        while (i := self.take(from_back=True)) is not None:
            self.run(i, executor)

    def values(self) -> list:
        """The folds' values in order, or the first failing fold's exception."""
        if self.failed:
            raise self.failed[min(self.failed)]
        values = []
        for i in range(len(self.items)):
            value, raised = self.done[i]
            raise_again(raised)
            values.append(value)
        return values
