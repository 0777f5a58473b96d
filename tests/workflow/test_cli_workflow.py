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
from helpers.truth import b_true, k_true
from thermaxis.cli import main

# The lines dataset's targets (helpers.builders.write_dataset's default).
POSITIONS_MM = np.array([0.0, 50.0, 100.0, 150.0])


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
    """c = -(e(T) - e(T at homing)), e = k x / 1000 + b: k and b fitted with numpy least
    squares to the exact lines of the other runs (x from the first target, which is 0 here)."""
    sensors = json.loads((folder / "model.json").read_text())["sensors"]
    wide = temperatures.pivot(index=["run", "measurement"], columns="sensor", values="absolute_c")
    absolute = wide[sensors]
    relative = absolute - absolute.groupby(level="run").transform("first")
    runs = absolute.index.get_level_values("run")
    r = np.array([LINES_RUNS.index(run) for run in runs])
    m = absolute.index.get_level_values("measurement").to_numpy() - 1
    train = runs != fold

    def fit_predict(inputs, target):
        design = np.column_stack([np.ones(len(inputs)), inputs.to_numpy()])
        coef, *_ = np.linalg.lstsq(design[train], target[train], rcond=None)
        return pd.Series(design @ coef, index=inputs.index).loc[fold]

    k = fit_predict(absolute, k_true(r, m))
    b = fit_predict(relative, b_true(r, m))
    error = k.to_numpy()[:, None] * POSITIONS_MM / 1000.0 + b.to_numpy()[:, None]
    change = pd.DataFrame(-(error - error[0]), index=k.index, columns=POSITIONS_MM)
    wanted = pd.MultiIndex.from_arrays([residuals["measurement"], residuals["position_mm"]])
    return change.stack().reindex(wanted).to_numpy()
