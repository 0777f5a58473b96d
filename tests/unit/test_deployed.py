"""The compensation's library path (thermaxis.compensation.deployed), without Snakemake:
the verdict's tolerance over the stroke the model's positions span, worked out by hand, and
a fold's model compensating its held-out run of an exact line to nothing."""

import json
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from helpers import DEFAULTS
from helpers.builders import HOLD, held_out_summary
from thermaxis.compensation.deployed import Deployment, fit_deployed, held_out_run, with_verdict
from thermaxis.compensation.runtime import Compensator
from thermaxis.compensation.verdict import verdict_sentence
from thermaxis.config import CompensationSettings
from thermaxis.method.folds import FoldSelection
from thermaxis.method.selection import SensitivePoints

SETTINGS = CompensationSettings("recommended", 0.5, 0.1, 0.05, "decoupled", "mlr", HOLD)
CHOICE = {"final": {"name": "super learner"}}
# Largest |deviation| 6 um: 5.88 after compensating on R1 (-0.12 um), 5.5 on R2 to R5; E as it was.
SUMMARY = held_out_summary(
    [("R1", 1, 6.0, 5.88, 2.0, 2.0)] + [(f"R{i}", 1, 6.0, 5.5, 2.0, 2.0) for i in range(2, 6)]
)


def _deployment(positions_mm):
    fitted = {"positions_mm": positions_mm, "deployment": {"model": "recommended"}}
    return with_verdict(fitted, SUMMARY, CHOICE, SETTINGS)["deployment"]


def test_a_long_stroke_resolves_less_and_leaves_the_smaller_change_unchanged():
    # 185 to 445 mm: 260 mm x 0.5 um/m = 0.13 um, so R1's -0.12 um is within it. Four of
    # five improve: p = P(X >= 4), X ~ B(5, 1/2) = 6/32 > 0.05.
    deployment = _deployment([185.0, 305.0, 445.0])
    verdict = deployment["verdict"]
    assert verdict["tolerance_um"] == pytest.approx(0.13, abs=1e-12)
    assert (verdict["improved_runs"], verdict["unchanged_runs"]) == (4, 1)
    assert verdict["sign_test_p"] == pytest.approx(6 / 32, abs=1e-12)
    assert deployment["outcome"] == "not_established"
    assert deployment["recommended_for_deployment"] is False
    assert deployment["recommended_by_the_evidence"] == "super learner"
    assert deployment["sentence"] == verdict_sentence(verdict)


def test_a_short_stroke_falls_to_the_floor_and_every_run_improves():
    # 100 mm x 0.5 um/m = 0.05 um, below the 0.1 um floor; R1's -0.12 um is beyond it.
    # Five of five: p = 1/32 <= 0.05, and the median change (-0.5 um) is a reduction.
    deployment = _deployment([0.0, 50.0, 100.0])
    verdict = deployment["verdict"]
    assert verdict["tolerance_um"] == pytest.approx(0.1, abs=1e-12)
    assert verdict["improved_runs"] == 5
    assert verdict["sign_test_p"] == pytest.approx(1 / 32, abs=1e-12)
    assert deployment["outcome"] == "recommended"
    assert deployment["recommended_for_deployment"] is True


# ------------------------------------------------------------- a held-out run of an exact line

TARGETS = np.array([185.0, 245.0, 305.0, 385.0, 445.0])


def _exact_runs():
    """Three runs whose unzeroed error is exactly k x + b: k = -300 + 13 T1 [um/m] on the
    absolute T1, b = -0.5 - 11 dT2 [um] on T2's rise since the first measurement."""
    rows, curves = [], []
    for r in range(3):
        for m in range(6):
            t1, rise = 28.0 + r + 0.8 * m + 0.3 * m * m, 0.5 * m + 0.05 * r * m
            rows.append({"run": f"R{r}", "measurement": m + 1, "time_min": 20.0 * m,
                         "T1": t1, "T2": 25.0 + 0.4 * r + rise})  # fmt: skip
            curves.append((-300.0 + 13.0 * t1) * (TARGETS - 185.0) / 1000.0 - 0.5 - 11.0 * rise)
    return pd.DataFrame(rows), pd.DataFrame(curves, columns=TARGETS)


def _point(sensor):
    return SensitivePoints(clusters=((sensor,),), selected=(sensor,), grades={sensor: 1.0}, eta=0.5)


def test_the_paper_model_of_a_fold_compensates_its_held_out_exact_line_to_nothing():
    # compensation.model: paper, decoupled MLR on the models rule's selection of fold R1
    # (k on T1, b on T2). R1 lies inside the other runs' temperatures, so nothing is held.
    X, Y = _exact_runs()
    d = Deployment(
        X=X,
        Y=Y,
        approach="decoupled",
        signals=(),
        decoupling=DEFAULTS.decoupling,
        compensation=replace(DEFAULTS.compensation, model="paper", algorithm="mlr"),
        selection=DEFAULTS.selection,
        models=DEFAULTS.models,
        steps={run: {"T1": 0.01, "T2": 0.01} for run in ("R0", "R1", "R2")},
        selections={"R1": FoldSelection("R1", k=_point("T1"), b=_point("T2"))},
    )
    record = fit_deployed(d, None, "R1", dataset="exact")
    final = Compensator(record)

    def unread():
        raise AssertionError("no time-aware input: the run's log is not read")

    # Each measurement's deviations, both passes, are the exact curve of that measurement.
    held = Y.loc[(X["run"] == "R1").to_numpy()].to_numpy()
    deviations = {m + 1: {"+": held[m], "-": held[m]} for m in range(6)}
    text, tables = held_out_run(d, "R1", {}, final, deviations, unread, dataset="exact")
    assert json.loads(text)["inputs"] == record["inputs"]
    residuals = tables["residuals"]
    # Drift since homing, 13 dT1 x - 11 dT2 [um], worked out here; the compensation takes
    # all of it.
    x_m = (residuals["position_mm"].to_numpy() - 185.0) / 1000.0
    by_m = X.loc[X["run"] == "R1"].set_index("measurement")
    m = residuals["measurement"].to_numpy()
    d_t1 = by_m.loc[m, "T1"].to_numpy() - by_m.loc[1, "T1"]
    d_t2 = by_m.loc[m, "T2"].to_numpy() - by_m.loc[1, "T2"]
    drift = 13.0 * d_t1 * x_m - 11.0 * d_t2
    assert residuals["uncompensated_um"].to_numpy() == pytest.approx(drift, abs=1e-9)
    assert np.abs(drift).max() > 10.0
    assert residuals["residual_um"].to_numpy() == pytest.approx(0.0, abs=1e-6)
