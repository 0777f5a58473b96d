"""tools.bench.records: the bench's comparison of the recommendation with the plain baseline."""

from __future__ import annotations

import pandas as pd
import yaml

from helpers import REPO
from tools.bench.records import channel_mapping, record_quality, without_signals


def test_record_quality_reads_the_workflows_tables(tmp_path):
    results = tmp_path / "rec"
    (results / "tables").mkdir(parents=True)
    (results / "recommend").mkdir()
    pd.DataFrame({"fold": ["A", "B"], "rmse_um": [1.0, 3.0], "paper_rmse_um": [4.0, 4.0]}).to_csv(
        results / "tables" / "recommendation.csv", index=False
    )
    pd.DataFrame(
        {"candidate": ["paper", "baseline-ridge+lags", "evidence-ridge"],
         "loco_rmse_um": [4.0, 2.5, 1.6]}
    ).to_csv(results / "recommend" / "candidates.csv", index=False)  # fmt: skip
    q = record_quality(results)
    # Mean 2.0 against the better reference 1.6 (1.25 x, above 1.10) and 4.0 (0.5 x).
    assert (q["recommended_rmse_um"], q["vs_references"], q["vs_paper"]) == (2.0, 1.25, 0.5)
    assert (q["baseline_rmse_um"], q["evidence_rmse_um"]) == (2.5, 1.6)
    assert not q["met"] and q["folds"] == 2


def test_channel_mapping_swaps_the_displacement_channel_only():
    mapping = REPO / "data" / "import" / "fl_thermal.yaml"
    spec = channel_mapping(mapping, 3)
    assert spec["name"] == "fl_thermal_ch3"
    assert spec["errors"]["columns"] == [{"column": "ch3(um)", "position_mm": 0}]
    assert spec["source"].endswith("data.xlsx") and spec["source"].startswith("/")
    assert "ch3" in spec["description"] and spec["split"]["signal"] == "spindle_rpm"


def test_without_signals_drops_the_declaration_and_the_logs(tmp_path):
    dataset = tmp_path / "ch2"
    (dataset / "R1" / "signals").mkdir(parents=True)
    (dataset / "R1" / "temperatures").mkdir()
    (dataset / "dataset.yaml").write_text(
        "name: fl_thermal_ch2\nsignals:\n- {id: spindle_rpm, unit: rpm}\n", encoding="utf-8"
    )
    without_signals(dataset)
    spec = yaml.safe_load((dataset / "dataset.yaml").read_text(encoding="utf-8"))
    assert spec == {"name": "fl_thermal_ch2"}
    assert not (dataset / "R1" / "signals").exists() and (dataset / "R1" / "temperatures").is_dir()
