"""``thermaxis compensate`` against the workflow: the controller's values of each held-out run.

The log given to the command is the held-out run's temperatures at its measurements,
taken from ``assembled/temperatures.parquet``. The compensation the controller computes
from the command's K0, tan(beta) and P0 must be the paper's decoupled MLR worked out here
with numpy: k on the absolute and b on the run-relative temperatures of the sensors the
model selected, fitted to the exact lines the ``lines`` dataset was written from
(helpers.truth) on the other runs.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from helpers.runs import LINES_RUNS
from helpers.truth import LINES_POSITIONS, lines_mlr_by_hand
from thermaxis.cli import main


@pytest.mark.parametrize("fold", LINES_RUNS)
def test_compensate_replays_residuals_csv(fold, lines_run, tmp_path, capsys):
    temperatures = pd.read_parquet(lines_run.out / "assembled" / "temperatures.parquet")
    wide = (
        temperatures[temperatures["run"] == fold]
        .pivot(index=["measurement", "time_min"], columns="sensor", values="absolute_c")
        .reset_index()
    )
    wide.insert(0, "time_s", wide["time_min"] * 60.0)
    log = tmp_path / "log.csv"
    wide.drop(columns=["measurement", "time_min"]).to_csv(log, index=False, float_format="%.17g")
    folder = lines_run.out / "compensation" / "folds" / fold
    out = tmp_path / "applied.csv"
    assert main(["compensate", str(folder / "model.json"), str(log), "--out", str(out)]) == 0
    assert f"wrote {out} ({len(wide)} cycles" in capsys.readouterr().out
    assert out.with_suffix(".png").read_bytes()[:4] == b"\x89PNG"

    applied = pd.read_csv(out).set_index("cycle")
    residuals = pd.read_csv(folder / "residuals.csv", comment="#")
    cycle = applied.loc[residuals["measurement"].to_numpy()]
    x_mm = residuals["position_mm"].to_numpy()
    # The controller's line: (K0 + tan(beta) (x - P0)) in mm, as um.
    line_um = (
        cycle["k0_mm"].to_numpy()
        + cycle["tan_beta"].to_numpy() * (x_mm - cycle["p0_mm"].to_numpy())
    ) * 1000.0
    assert line_um == pytest.approx(_compensation_by_hand(temperatures, folder, fold, residuals),
                                    rel=1e-6, abs=1e-6)  # fmt: skip
    assert (cycle["status"] == "ok").all()
    assert cycle["status"].tolist() == residuals["status"].tolist()


def _compensation_by_hand(temperatures, folder, fold, residuals) -> np.ndarray:
    """c = -(e(T) - e(T at homing)): the decoupled MLR's error change since the first
    measurement, on the model's inputs for k and b (helpers.truth.lines_mlr_by_hand)."""
    model = json.loads((folder / "model.json").read_text())
    inputs = {
        reg["target"]: tuple(model["inputs"][i]["sensor"] for i in reg["inputs"])
        for reg in model["regressions"]
    }
    _, predicted = lines_mlr_by_hand(temperatures, {**inputs, "pointwise": ()}, fold, LINES_RUNS)
    error = predicted["decoupled"]
    measurements = np.arange(1, len(error) + 1)
    change = pd.DataFrame(-(error - error[0]), index=measurements, columns=LINES_POSITIONS)
    wanted = pd.MultiIndex.from_arrays([residuals["measurement"], residuals["position_mm"]])
    return change.stack().reindex(wanted).to_numpy()
