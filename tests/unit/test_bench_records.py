"""tools.bench.records: the bench's comparison of the recommendation with the plain baseline."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
import yaml
from scipy.optimize import nnls

from helpers import REPO
from thermaxis.method.nested import COMBINED, super_learner_weights
from tools.bench.records import channel_mapping, record_quality, without_signals
from tools.bench.replay import main as replay_main
from tools.bench.replay import replay, replay_markdown, with_table
from tools.bench.report import _quality_table
from tools.bench.stacking import BLOCKS, STACKS, stacked_rmse
from tools.bench.stacking import main as stacking_main


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
    (results / "compensation").mkdir()
    verdict = {"outcome": "not_established", "improved_runs": 1, "worsened_runs": 1,
               "held_out_runs": 3, "untested_runs": 1, "sign_test_p": 0.875}  # fmt: skip
    (results / "compensation" / "model.json").write_text(
        json.dumps({"deployment": {"verdict": verdict}}), encoding="utf-8"
    )
    q = record_quality(results)
    # Mean 2.0 against the better reference 1.6 (1.25 x, above 1.10) and 4.0 (0.5 x).
    assert (q["recommended_rmse_um"], q["vs_references"], q["vs_paper"]) == (2.0, 1.25, 0.5)
    assert (q["baseline_rmse_um"], q["evidence_rmse_um"]) == (2.5, 1.6)
    assert not q["met"] and q["folds"] == 2
    assert (q["verdict"], q["improved_runs"], q["worsened_runs"], q["sign_test_p"]) == (
        "not_established",
        1,
        1,
        0.875,
    )
    # The bench table's verdict cell names the untested run (held throughout by the fallback).
    assert "| not established (1 / 1 of 3, 1 untested, p = 0.88) |" in "\n".join(
        _quality_table([q], "a test record")
    )


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


def _toy_scores():
    """Three runs; inner RMSE favours the evidence ridge, inner largest |residual| the
    paper's configuration; held out: paper 4, ridge with lags 3, evidence ridge 2 µm, the
    super learner 2.5 µm."""
    rows = [{"kind": "loco", "fold": run, "candidate": COMBINED, "held_out": run, "rmse": 2.5,
             "max_abs": 2.5, "mae": 0.0, "residual_min": 0.0, "residual_max": 0.0}
            for run in ("A", "B", "C")]  # fmt: skip
    inner = {"paper": (9.0, 1.0), "baseline-ridge+lags": (5.0, 5.0), "evidence-ridge": (1.0, 6.0)}
    outer = {"paper": 4.0, "baseline-ridge+lags": 3.0, "evidence-ridge": 2.0}
    runs = ["A", "B", "C"]
    for fold in runs:
        for name in inner:
            rows.append({"kind": "loco", "fold": fold, "candidate": name, "held_out": fold,
                         "rmse": outer[name], "max_abs": outer[name], "mae": 0.0,
                         "residual_min": 0.0, "residual_max": 0.0})  # fmt: skip
            for held in (r for r in runs if r != fold):
                rmse, max_abs = inner[name]
                rows.append({"kind": "inner", "fold": fold, "candidate": name, "held_out": held,
                             "rmse": rmse, "max_abs": max_abs, "mae": 0.0,
                             "residual_min": 0.0, "residual_max": 0.0})  # fmt: skip
    return pd.DataFrame(rows)


def test_the_replay_applies_each_rule_to_the_inner_scores_alone(tmp_path):
    figures = replay(_toy_scores())
    # The super learner as deployed: 2.5 µm. Lowest mean inner RMSE: the evidence ridge in every fold, 2 µm held out; lowest inner
    # largest |residual|: the paper's configuration, 4 µm; the previous rule: two inner
    # runs give a signed-rank p of at least 1/4, so the ridge with lags stands, 3 µm.
    assert list(figures.values()) == [2.5, 2.0, 4.0, 3.0, 4.0, 3.0, 2.0]
    table = replay_markdown({"toy": _toy_scores()})
    assert "| **super learner of `recommend.combine`** (deployed) | 2.50 (1.25) |" in table
    assert "| lowest mean inner RMSE (replaced) | 2.00 (1.00) |" in table
    assert "| the paper's configuration always | 4.00 (2.00) |" in table
    # 2.5 / 2.0 = 1.25 > 1.10; 2.5 / 4.0 = 0.625 <= 1.
    assert table.endswith(
        "on 0 of 1 records; it misses them on toy (1.25 x the better reference, 0.62 x the "
        "paper's).\n"
    )
    doc = tmp_path / "doc.md"
    doc.write_text("before\n<!-- replay:start -->\nold\n<!-- replay:end -->\nafter\n")
    doc.write_text(with_table(doc.read_text(), table))
    assert doc.read_text() == f"before\n<!-- replay:start -->\n{table}<!-- replay:end -->\nafter\n"


def test_stacking_weights_by_hand_and_by_scipy():
    # Three candidates on four rows: the measurement is exactly 1/4 of the first plus 3/4
    # of the second; the third is unrelated. The least-squares weights are (1/4, 3/4, 0),
    # non-negative and summing to one without scaling.
    a = np.array([1.0, 0.0, 2.0, -1.0])
    b = np.array([0.0, 1.0, 1.0, 3.0])
    c = np.array([5.0, -4.0, 0.5, 0.0])
    P = np.column_stack([a, b, c])
    np.testing.assert_allclose(super_learner_weights(P, 0.25 * a + 0.75 * b), [0.25, 0.75, 0.0],
                               atol=1e-12)  # fmt: skip
    # Twice the measurement: scipy's NNLS gives (0.5, 1.5, 0), scaled to sum to one.
    y = 0.5 * a + 1.5 * b
    raw, _ = nnls(P, y)
    np.testing.assert_allclose(super_learner_weights(P, y), raw / raw.sum(), atol=1e-12)
    np.testing.assert_allclose(super_learner_weights(P, y), [0.25, 0.75, 0.0], atol=1e-12)
    # No candidate helps (every weight zero): equal weights.
    np.testing.assert_allclose(super_learner_weights(np.abs(P), -np.ones(4)), [1 / 3] * 3)


def test_stacked_rmse_weights_each_outer_fold_on_its_inner_runs_alone():
    # Three runs of two readings, all measured 0. Member A predicts 1 for every run from
    # every training set, member B 3 for R1 and 0 for the others whatever it was fitted on.
    runs = ["R1", "R2", "R3"]
    X = pd.DataFrame({"run": np.repeat(runs, 2)})
    Y = pd.DataFrame({"e": np.zeros(6)})
    value = {"A": dict.fromkeys(runs, 1.0), "B": {"R1": 3.0, "R2": 0.0, "R3": 0.0}}
    predicted = {}
    for train in [(a, b) for a in runs for b in runs if a < b] + [(r,) for r in runs]:
        scored = [r for r in runs if r not in train]
        for name in ("A", "B"):
            predicted[(train, name)] = (
                np.repeat(scored, 2),
                np.repeat([value[name][r] for r in scored], 2)[:, None],
            )
    # Holding out R1, the inner runs R2 and R3 favour B (0 against 1): R1's error is B's, 3.
    # Holding out R2 (or R3), the inner runs are R1 (B 3, A 1) and R3 (B 0, A 1): the mean
    # run RMSE is 1 for A and 1.5 for B, so the selector takes A, an error of 1. Mean: 5/3.
    select = STACKS["the better of the two plain references by mean run RMSE (`select`)"][1]
    assert stacked_rmse(X, Y, ["A", "B"], predicted, select) == pytest.approx(5 / 3)
    # The convex weights on R2's fold: |w + 3(1 - w)| on R1 and |w| on R3 have the mean
    # (3 - 2w + w) / 2, lowest at w = 1 (A alone); R1's fold has B alone (0 on both): 5/3 again.
    _, rmse, *_ = STACKS[
        "super learner, the two plain references, lowest mean run RMSE, weighed on fits of one run too"
    ]
    assert stacked_rmse(X, Y, ["A", "B"], predicted, rmse) == pytest.approx(5 / 3, abs=1e-6)
    # The deployed rule: every inner fit here holds one run, so each fold weights A and B
    # equally. R1: (1 + 3) / 2 = 2; R2 and R3: (1 + 0) / 2 = 0.5. Mean: 1.
    _, rmse, min_runs = STACKS[
        "super learner, the two plain references, lowest mean run RMSE (`rmse`, deployed)"
    ]
    assert min_runs == 2
    assert stacked_rmse(X, Y, ["A", "B"], predicted, rmse, min_runs) == pytest.approx(1.0)


def test_stacked_rmse_of_a_two_run_record_weights_every_row_equally():
    # Two runs of two readings, measured 0 and 2. Fitted on the other run, member A predicts
    # 1 everywhere and member B 4 for R1 and 0 for R2. No fold has an inner fit, so every
    # row weighs them equally, whatever its weighting: R1 |0 - (1 + 4) / 2| = 2.5, R2
    # |2 - (1 + 0) / 2| = 1.5; mean 2.
    X = pd.DataFrame({"run": ["R1", "R1", "R2", "R2"]})
    Y = pd.DataFrame({"e": [0.0, 0.0, 2.0, 2.0]})
    predicted = {
        (("R2",), "A"): (np.array(["R1", "R1"]), np.ones((2, 1))),
        (("R2",), "B"): (np.array(["R1", "R1"]), np.full((2, 1), 4.0)),
        (("R1",), "A"): (np.array(["R2", "R2"]), np.ones((2, 1))),
        (("R1",), "B"): (np.array(["R2", "R2"]), np.zeros((2, 1))),
    }
    for _, stack, *min_runs in STACKS.values():
        assert stacked_rmse(X, Y, ["A", "B"], predicted, stack, *min_runs) == pytest.approx(2.0)


def test_the_replay_command_writes_the_table_into_the_document(tmp_path, capsys):
    scores = _toy_scores()
    folds = tmp_path / "results" / "toy" / "recommend" / "folds"
    folds.mkdir(parents=True)
    for fold, rows in scores.groupby("fold"):
        rows.to_csv(folds / f"{fold}.csv", index=False)
    doc = tmp_path / "doc.md"
    doc.write_text("<!-- replay:start -->\n<!-- replay:end -->\n")
    assert replay_main([str(tmp_path / "results"), "--doc", str(doc)]) == 0
    assert (
        doc.read_text()
        == f"<!-- replay:start -->\n{replay_markdown({'toy': scores})}<!-- replay:end -->\n"
    )
    (tmp_path / "empty").mkdir()
    assert replay_main([str(tmp_path / "empty")]) == 2
    assert "no <record>/recommend/folds/*.csv" in capsys.readouterr().err


def test_the_stacking_command_names_a_block_it_does_not_know_in_one_line(tmp_path, capsys):
    assert stacking_main([str(tmp_path), "--block", "scored"]) == 2
    assert capsys.readouterr().err == (
        "thermaxis error: --block 'scored': expected one of records, dev, three-runs, "
        "measured-cuts\n"
    )
    assert BLOCKS["dev"] == ("<!-- stacking-dev:start -->", "<!-- stacking-dev:end -->")
