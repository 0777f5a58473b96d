"""The calibration's last leg: the compass search on a faithfulness table."""

from __future__ import annotations

import numpy as np
import pandas as pd

from thermaxis.twin import model as mdl
from thermaxis.twin import polish as pol

RUNS = ("E1", "E2", "E3", "E4")


def _table(rows: list[tuple[str, float]]) -> pd.DataFrame:
    """A faithfulness table with margins: a target holds where its margin is >= 0."""
    return pd.DataFrame(
        [dict(target=t, holds="yes" if m >= 0 else "no", margin=m) for t, m in rows]
    )


def test_fewer_failures_rank_first_then_shortfall_then_the_repaired_margin():
    one_far = _table([("a", -0.5), ("b", 0.9)])
    one_near = _table([("a", -0.1), ("b", 0.9)])
    two_near = _table([("a", -0.01), ("b", -0.01)])
    none_low = _table([("a", 0.05), ("b", 0.9)])
    none_high = _table([("a", 0.4), ("b", 0.01)])
    repaired = frozenset({"a"})
    order = sorted(
        [two_near, one_far, none_low, one_near, none_high], key=lambda t: pol.rank(t, repaired)
    )
    # By hand: 0 failures before 1 before 2; between 0-failure tables, a's margin decides
    # (0.4 > 0.05) although b's is smaller in the first; between 1-failure ones, 0.1 < 0.5.
    assert [id(t) for t in order] == [
        id(t) for t in (none_high, none_low, one_near, one_far, two_near)
    ]


def _evaluate(params: mdl.TwinParams) -> pd.DataFrame:
    # Target "heat" holds within 0.1 W/(m/min) of 1.5 W/(m/min) of nut heat; "gain" within
    # 0.4 um/m/K of the committed screw gain, so a step of the gain itself breaks it.
    heat = params.values["nut_heat_W_per_m_min"]
    gain = params.values["screw_gain_um_per_m_K"]
    return _table(
        [("heat", (0.1 - abs(heat - 1.5)) / 0.1), ("gain", (0.4 - abs(gain - 8.0)) / 0.4)]
    )


def test_the_search_takes_the_step_that_repairs_and_stops_when_all_hold():
    start = mdl.load_params(mdl.PARAMS_PATH)
    values = dict(start.values, nut_heat_W_per_m_min=1.70, screw_gain_um_per_m_K=8.0)
    params, record = pol.polish(mdl.TwinParams(values, start.initial), _evaluate, workers=1)
    # Nut heat's range is 0-6 W/(m/min): the first step is 0.02 x 6 = 0.12 down, to 1.58,
    # inside 1.5 +- 0.1, and every target then holds; no other parameter moves.
    assert np.isclose(params.values["nut_heat_W_per_m_min"], 1.58)
    assert record["moves"] == ["nut_heat_W_per_m_min -0.02 of its range"]
    assert record["failing"] == 0
    moved = params.vector(RUNS) != np.round(mdl.TwinParams(values, start.initial).vector(RUNS), 6)
    assert np.flatnonzero(moved).tolist() == [0]
    # One start, then one sweep: every parameter down and up, less those at a bound.
    lower, upper = mdl.parameter_bounds(RUNS)
    x = np.round(mdl.TwinParams(values, start.initial).vector(RUNS), 6)
    at_bound = int(np.sum(x == lower) + np.sum(x == upper))
    assert record["evaluations"] == 1 + 2 * x.size - at_bound


def test_a_search_that_starts_where_everything_holds_changes_nothing():
    start = mdl.load_params(mdl.PARAMS_PATH)
    values = dict(start.values, nut_heat_W_per_m_min=1.5, screw_gain_um_per_m_K=8.0)
    params, record = pol.polish(mdl.TwinParams(values, start.initial), _evaluate, workers=1)
    assert params.values["nut_heat_W_per_m_min"] == 1.5
    assert record["moves"] == [] and record["evaluations"] == 1


def test_the_committed_twin_holds_every_published_target_through_the_pipeline():
    # The polish's own judge on the committed parameters: their raw files, written afresh
    # and run through the pipeline on fold E4, against the paper's published values.
    from thermaxis.twin.calibration import faithfulness_of

    table = faithfulness_of(mdl.load_params(mdl.PARAMS_PATH))
    assert len(table) == 17
    assert table.loc[table["holds"] == "no", "target"].tolist() == []
    svr = table[table["target"].str.startswith("Table 8: decoupled SVR, largest")]
    assert abs(float(svr["reproduced"].iloc[0]) - 1.0) <= 0.3
