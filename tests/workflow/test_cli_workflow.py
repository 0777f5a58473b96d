"""``thermaxis compensate`` against the workflow: the controller's values of each held-out run.

The log given to the command is the held-out run's temperatures at its measurements,
taken from ``assembled/temperatures.parquet``; the compensation the controller computes
from the command's K0, tan(beta) and P0 must be ``residuals.csv``'s, and the fallback
status of each cycle the workflow's.
"""

from __future__ import annotations

import pandas as pd
import pytest

from helpers.runs import LINES_RUNS
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
    # The controller's line: (K0 + tan(beta) (x - P0)) in mm, as um.
    line_um = (
        cycle["k0_mm"].to_numpy()
        + cycle["tan_beta"].to_numpy()
        * (residuals["position_mm"].to_numpy() - cycle["p0_mm"].to_numpy())
    ) * 1000.0
    # residuals.csv holds 10 significant digits.
    assert line_um == pytest.approx(residuals["compensation_um"].to_numpy(), rel=1e-9, abs=1e-9)
    assert cycle["status"].tolist() == residuals["status"].tolist()
