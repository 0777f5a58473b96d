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


def test_a_recommendation_fold_is_worth_a_worker_of_its_own():
    assert [fold_workers(2, n, "recommend") for n in (1, 2, 4, 43)] == [1, 2, 2, 2]
    assert fold_workers(16, 6, "recommend") == 6


@pytest.mark.parametrize("workers", [1, 2])
def test_workers_return_in_order_and_raise_their_warnings_here(workers):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        values = map_folds(partial(_square_warning_on_odd, 3), list(range(6)), workers)
    assert values == [0, 3, 12, 27, 48, 75]
    assert [(w.category, str(w.message)) for w in caught] == [
        (SelectionWarning, f"fold {n}: odd") for n in (1, 3, 5)
    ]
