"""tools.bench.records: the bench's comparison of the recommendation with the plain baseline."""

from __future__ import annotations

import pandas as pd

from helpers import REPO
from tools.bench.records import channel_mapping, record_quality


def test_record_quality_reads_the_workflows_tables(tmp_path):
    results = tmp_path / "rec"
    (results / "tables").mkdir(parents=True)
    (results / "recommend").mkdir()
    pd.DataFrame({"fold": ["A", "B"], "rmse_um": [1.0, 3.0], "paper_rmse_um": [4.0, 4.0]}).to_csv(
        results / "tables" / "recommendation.csv", index=False
    )
    pd.DataFrame(
        {"candidate": ["paper", "baseline-ridge+lags"], "loco_rmse_um": [4.0, 2.5]}
    ).to_csv(results / "recommend" / "candidates.csv", index=False)
    q = record_quality(results)
    # Mean 2.0 against 2.5 (0.8 x) and 4.0 (0.5 x): both bounds hold.
    assert (q["recommended_rmse_um"], q["vs_baseline"], q["vs_paper"]) == (2.0, 0.8, 0.5)
    assert q["met"] and q["folds"] == 2


def test_channel_mapping_swaps_the_displacement_channel_only():
    mapping = REPO / "data" / "import" / "fl_thermal.yaml"
    spec = channel_mapping(mapping, 3)
    assert spec["name"] == "fl_thermal_ch3"
    assert spec["errors"]["columns"] == [{"column": "ch3(um)", "position_mm": 0}]
    assert spec["source"].endswith("data.xlsx") and spec["source"].startswith("/")
    assert "ch3" in spec["description"] and spec["split"]["signal"] == "spindle_rpm"
