"""The paper's temperature-side targets of the calibration: its own fitted models.

The paper fitted Eq. 9 (the decoupled MLR: k on absolute T1, T6, T12; b on T2, T7, T11
relative to the run's first measurement) and Eq. 8 (the point-by-point MLR on T1, T11,
T12 relative to the run start; printed only at 185, 205, 225 and 445 mm) to ITS data.
A twin whose temperatures are faithful to the paper's should give back its own k, b
and errors when those equations are applied to its sensors.  Coefficients and the
error bounds (Table 7) are read from the transcriptions in ``thermaxis/paper/values/``; nothing
from the pipeline's held-out results enters here.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from thermaxis.paper.published import load_table

__all__ = ["PublishedModel", "PublishedTargets", "published_targets"]


@dataclass(frozen=True)
class PublishedModel:
    """One printed regression: ``const + sum(coef[s] * T_s)``."""

    const: float
    coef: dict[str, float]
    relative: bool  # temperatures relative to the run's first measurement

    def predict(self, temperatures: Mapping[str, np.ndarray]) -> np.ndarray:
        """Prediction for one run's measurements (arrays in measurement order)."""
        out = np.full(len(next(iter(temperatures.values()))), self.const)
        for sensor, c in self.coef.items():
            t = np.asarray(temperatures[sensor], dtype=float)
            out = out + c * (t - t[0] if self.relative else t)
        return out


@dataclass(frozen=True)
class PublishedTargets:
    """Eq. 9, the printed rows of Eq. 8, and the paper's Table 7 bounds."""

    k: PublishedModel
    b: PublishedModel
    pointwise: dict[float, PublishedModel]  # position (mm) -> Eq. 8 row
    bound_k_um_per_m: float
    bound_b_um: float
    bound_error_um: float


def _model(rows) -> PublishedModel:
    const = float(rows.loc[rows["term"] == "const", "value"].iloc[0])
    terms = rows[rows["term"] != "const"]
    return PublishedModel(
        const=const,
        coef=dict(zip(terms["term"], terms["value"].astype(float), strict=False)),
        relative=bool((rows["temperature"] == "relative").all()),
    )


def published_targets(paper_dir=None) -> PublishedTargets:
    """Read Eq. 8, Eq. 9 and Table 7 from the paper's transcriptions."""
    eq9 = load_table("eq9", paper_dir)
    eq8 = load_table("eq8", paper_dir)
    metrics = load_table("prediction_metrics", paper_dir)
    table7 = metrics[(metrics["table"] == 7) & (metrics["algorithm"] == "mlr")].set_index("target")[
        "rmse"
    ]
    return PublishedTargets(
        k=_model(eq9[eq9["target"] == "k"]),
        b=_model(eq9[eq9["target"] == "b"]),
        pointwise={float(x): _model(rows) for x, rows in eq8.groupby("position_mm", sort=True)},
        bound_k_um_per_m=float(table7["k"]),
        bound_b_um=float(table7["b"]),
        bound_error_um=float(table7["error"]),
    )
