"""Slope/intercept decoupling of a positioning-error curve (the paper's Eq. 6).

Each measurement's errors e(x) at the targets are fitted by least squares on the
*shifted* stroke ``x - x_first`` (185 ... 445 mm becomes 0 ... 260 mm in the paper),
so that the intercept b is the error at the first target and the slope k is in
um per metre of travel.  Degrees 2 and 3 are offered because the paper names a
strongly non-linear error curve as the method's limitation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "DecoupledFit",
    "decouple_measurement",
    "decouple_curves",
    "decouple_table",
    "compose_curve",
    "stroke_powers",
    "MM_PER_M",
]

MM_PER_M = 1000.0


@dataclass(frozen=True)
class DecoupledFit:
    """Result of decoupling one measurement.

    ``coefficients`` are in ascending powers of the shifted position in metres:
    c0 [um], c1 [um/m], c2 [um/m^2], ...; so ``k = c1`` and ``b = c0``.
    """

    k_um_per_m: float
    b_um: float
    r2: float
    rms_um: float
    coefficients: tuple[float, ...]
    origin_mm: float


def stroke_powers(position_mm, origin_mm: float, degree: int) -> np.ndarray:
    """(p, degree + 1): powers 0..degree of the shifted stroke in metres, Eq. 6's design matrix."""
    shifted_m = (np.asarray(position_mm, dtype=float) - origin_mm) / MM_PER_M
    return np.vander(shifted_m, degree + 1, increasing=True)


def decouple_measurement(
    position_mm, error_um, degree: int, origin_mm: float | None = None
) -> DecoupledFit:
    """Least-squares fit of one measurement's error curve by a polynomial of ``degree`` (1: the paper's line).

    ``origin_mm`` defaults to the smallest position (the first target); pass the
    dataset's first target explicitly when a measurement lost its first reading,
    so that b keeps the same meaning for every measurement.
    """
    x = np.asarray(position_mm, dtype=float)
    y = np.asarray(error_um, dtype=float)
    if x.shape != y.shape or x.ndim != 1:
        raise ValueError("position_mm and error_um must be 1-D arrays of equal length")
    if degree not in (1, 2, 3):
        raise ValueError(f"decoupling degree must be 1, 2 or 3, got {degree}")
    if np.unique(x).size < degree + 1:
        raise ValueError(
            f"decoupling of degree {degree} needs at least {degree + 1} distinct positions, got {np.unique(x).size}"
        )
    origin = float(np.min(x)) if origin_mm is None else float(origin_mm)
    design = stroke_powers(x, origin, degree)
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    fitted = design @ coef
    residual = y - fitted
    ss_res = float(residual @ residual)
    centred = y - y.mean()
    ss_tot = float(centred @ centred)
    # An exactly flat curve is perfectly explained by any fit.
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else 1.0
    rms = float(np.sqrt(ss_res / y.size))
    return DecoupledFit(
        k_um_per_m=float(coef[1]),
        b_um=float(coef[0]),
        r2=float(r2),
        rms_um=rms,
        coefficients=tuple(float(c) for c in coef),
        origin_mm=origin,
    )


def decouple_curves(
    position_mm, errors, degree: int, origin_mm: float | None = None, labels=None
) -> list[DecoupledFit]:
    """Decouple each row of an (n_measurements, n_positions) error matrix.

    Missing readings (NaN, or any non-finite value) are left out of their row's fit; ``origin_mm`` defaults to
    the first position, so every row's b refers to the same target. ``labels`` name
    the rows in the error raised when one cannot be fitted.
    """
    x = np.asarray(position_mm, dtype=float)
    matrix = np.asarray(errors, dtype=float)
    origin = float(x[0]) if origin_mm is None else float(origin_mm)
    fits = []
    for i, row in enumerate(matrix):
        valid = np.isfinite(row)
        try:
            fits.append(decouple_measurement(x[valid], row[valid], degree=degree, origin_mm=origin))
        except ValueError as exc:
            label = labels[i] if labels is not None else f"row {i}"
            raise ValueError(f"{label}: {exc}") from exc
    return fits


def compose_curve(coefficients, position_mm, origin_mm: float) -> np.ndarray:
    """The paper's Eq. 7, y = k x + b (and its curved forms), on the shifted stroke.

    ``coefficients`` are rows of ascending powers (b, k, c2, c3) as in
    :class:`DecoupledFit`; shape (n, degree + 1) gives curves of shape (n, p).
    """
    coefficients = np.atleast_2d(np.asarray(coefficients, dtype=float))
    return coefficients @ stroke_powers(position_mm, origin_mm, coefficients.shape[1] - 1).T


def decouple_table(errors, degree: int):
    """Decouple every measurement of a tidy errors table (run, measurement, time_min, position_mm, error_um).

    Returns ``(kb, coefficients)``: the Table 5 frame (run, measurement, time_min,
    k_um_per_m, b_um, r2, rms_um) and a long frame of all polynomial coefficients.
    The origin is each run's first target, so a measurement that lost its first
    reading keeps the same meaning of b.
    """
    import pandas as pd

    rows, coef_rows = [], []
    for run, run_errors in errors.groupby("run", sort=True):
        origin = float(run_errors["position_mm"].min())
        for measurement, m in run_errors.groupby("measurement", sort=True):
            valid = m.dropna(subset=["error_um"])
            fit = decouple_measurement(
                valid["position_mm"], valid["error_um"], degree=degree, origin_mm=origin
            )
            rows.append(
                (
                    run,
                    int(measurement),
                    float(m["time_min"].iloc[0]),
                    fit.k_um_per_m,
                    fit.b_um,
                    fit.r2,
                    fit.rms_um,
                )
            )
            for power, value in enumerate(fit.coefficients):
                coef_rows.append((run, int(measurement), power, value))
    kb = pd.DataFrame(
        rows, columns=["run", "measurement", "time_min", "k_um_per_m", "b_um", "r2", "rms_um"]
    )
    coefficients = pd.DataFrame(coef_rows, columns=["run", "measurement", "power", "value"])
    return kb, coefficients
