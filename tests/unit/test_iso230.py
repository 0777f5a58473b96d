"""ISO 230-2 single-pass quantities on small examples worked by hand."""

import math

import numpy as np
import pytest

from thermaxis.compensation.iso230 import (
    NEEDS_READINGS,
    NOT_COMPUTED,
    QUANTITIES,
    single_pass_quantities,
)


def test_three_targets_both_directions():
    # up 1, 3, 2; down 0, 1, 1 (um)
    # E_up = 3 - 1 = 2; E_down = 1 - 0 = 1; E = max(3) - min(0) = 3
    # means 0.5, 2, 1.5 -> M = 1.5; reversal 1, 2, 1 -> B = 2
    q = single_pass_quantities([1.0, 3.0, 2.0], [0.0, 1.0, 1.0])
    assert q == pytest.approx({"E_up": 2.0, "E_down": 1.0, "E": 3.0, "M": 1.5, "B": 2.0})


def test_negative_reversal_counts_by_its_size():
    # up 0, 0; down 0.5, 3 -> reversal -0.5, -3 -> B = 3; means 0.25, 1.5 -> M = 1.25; E = 3 - 0 = 3
    q = single_pass_quantities([0.0, 0.0], [0.5, 3.0])
    assert q == pytest.approx({"E_up": 0.0, "E_down": 2.5, "E": 3.0, "M": 1.25, "B": 3.0})


def test_missing_reading_drops_the_target_from_m_and_b_only():
    # up 1, -, 2; down 0, 5, 1 -> E_up = 1, E_down = 5, E = 5 - 0 = 5
    # targets read both ways: 1 and 3 -> means 0.5, 1.5 -> M = 1; reversal 1, 1 -> B = 1
    q = single_pass_quantities([1.0, np.nan, 2.0], [0.0, 5.0, 1.0])
    assert q == pytest.approx({"E_up": 1.0, "E_down": 5.0, "E": 5.0, "M": 1.0, "B": 1.0})


def test_one_pass_gives_its_own_e_only():
    q = single_pass_quantities(up=[2.0, -1.0, 0.5])
    assert q["E_up"] == pytest.approx(3.0)
    assert all(math.isnan(q[name]) for name in ("E_down", "E", "M", "B"))
    q = single_pass_quantities(down=[2.0, -1.0])
    assert q["E_down"] == pytest.approx(3.0) and math.isnan(q["E_up"])


def test_quantities_needing_repeated_cycles_are_named_not_computed():
    assert set(NOT_COMPUTED) >= {"R_up", "R_down", "R", "A_up", "A_down", "A"}
    assert not set(NOT_COMPUTED) & set(QUANTITIES)
    with pytest.raises(ValueError, match="at least one pass"):
        single_pass_quantities()


def test_one_target_has_no_span_but_its_reversal():
    # A single-point record: E_up, E_down and M are spans over one target (none); E spans
    # the two directions' readings 0.5 and -0.25 (0.75), B is their difference.
    q = single_pass_quantities([0.5], [-0.25])
    assert all(math.isnan(q[name]) for name in ("E_up", "E_down", "M"))
    assert (q["E"], q["B"]) == pytest.approx((0.75, 0.75))
    assert math.isnan(single_pass_quantities(up=[0.5])["E_up"])
    assert set(NEEDS_READINGS) == set(QUANTITIES)  # each one's note where it is not given
