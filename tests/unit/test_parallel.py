"""thermaxis.pipeline.parallel: the folds of a job in worker processes give what one
process gives, warnings included."""

from __future__ import annotations

import warnings
from functools import partial

import pytest

from thermaxis.errors import SelectionWarning
from thermaxis.pipeline.parallel import fold_workers, map_folds


def _square_warning_on_odd(scale, n):
    if n % 2:
        warnings.warn(f"fold {n}: odd", SelectionWarning, stacklevel=1)
    return scale * n * n


def test_fold_workers_take_four_folds_each_and_never_exceed_the_cores():
    assert [fold_workers(2, n, "models") for n in (1, 3, 4, 7, 8, 43)] == [1, 1, 1, 1, 2, 2]
    assert fold_workers(16, 43, "models") == 10


def test_the_recommendation_takes_a_second_worker_where_the_models_do():
    # The twin (4 folds) and fl_thermal (6) recommend in one process; 8 runs and more in two.
    counts = (1, 4, 6, 7, 8, 12, 43)
    assert [fold_workers(2, n, "recommend") for n in counts] == [1, 1, 1, 1, 2, 2, 2]
    assert [fold_workers(2, n, "recommend") for n in counts] == [
        fold_workers(2, n, "models") for n in counts
    ]
    assert fold_workers(16, 43, "recommend") == 10


@pytest.mark.parametrize("workers", [1, 2])
def test_workers_return_in_order_and_raise_their_warnings_here(workers):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        values = map_folds(partial(_square_warning_on_odd, 3), list(range(6)), workers)
    assert values == [0, 3, 12, 27, 48, 75]
    assert [(w.category, str(w.message)) for w in caught] == [
        (SelectionWarning, f"fold {n}: odd") for n in (1, 3, 5)
    ]


def _fold_in_some_process(marks, parent, n):
    """Fold ``n``, marked with its process; the job's process holds fold 0 until a worker
    has done a fold, so the two share the folds whatever the machine's speed."""
    import os
    import time

    (marks / f"{n}-{os.getpid()}").touch()
    if os.getpid() == parent and n == 0:
        deadline = time.monotonic() + 120  # a bound on a worker's start, not a measurement
        while not any(not m.name.endswith(f"-{parent}") for m in marks.iterdir()):
            assert time.monotonic() < deadline, "no worker took a fold"
            time.sleep(0.05)
    if n % 2:
        warnings.warn(f"fold {n}: odd", SelectionWarning, stacklevel=1)
    return n * n, os.getpid()


def test_the_jobs_process_and_a_worker_share_the_folds_from_both_ends(tmp_path):
    import os

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        values = map_folds(
            partial(_fold_in_some_process, tmp_path, os.getpid()), list(range(6)), workers=2
        )
    assert [value for value, _ in values] == [0, 1, 4, 9, 16, 25]
    by_process = {pid == os.getpid() for _, pid in values}
    assert by_process == {True, False}
    # The job's process from the front, the worker from the back.
    assert values[0][1] == os.getpid() and values[-1][1] != os.getpid()
    assert [str(w.message) for w in caught] == [f"fold {n}: odd" for n in (1, 3, 5)]


def _fails_on_two_and_four(n):
    if n in (2, 4):
        raise ValueError(f"fold {n} failed")
    return n


@pytest.mark.parametrize("workers", [1, 2])
def test_the_first_failing_folds_error_is_raised_as_in_one_process(workers):
    with pytest.raises(ValueError, match="^fold 2 failed$"):
        map_folds(_fails_on_two_and_four, list(range(6)), workers)
