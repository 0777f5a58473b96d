"""Decoupling: least squares on the shifted stroke, checked against hand-worked numbers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from helpers import DEFAULTS
from helpers.builders import write_dataset
from thermaxis.cleaning.run import clean_and_assemble_run
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.method.decouple import compose_curve, decouple_measurement, decouple_table


def test_hand_worked_line():
    # x = 185, 205, 225 mm -> shifted 0, 0.02, 0.04 m; e = 1, 2, 4 um.
    # xbar = 0.02, ebar = 7/3; Sxy = (-0.02)(1-7/3) + 0 + (0.02)(4-7/3) = 0.06
    # Sxx = 0.0008 -> k = 75 um/m; b = 7/3 - 75*0.02 = 5/6 um.
    fit = decouple_measurement([185, 205, 225], [1, 2, 4], degree=1)
    assert fit.k_um_per_m == pytest.approx(75.0, abs=1e-12)
    assert fit.b_um == pytest.approx(5 / 6, abs=1e-12)
    # residuals: 1-5/6, 2-(5/6+1.5), 4-(5/6+3) = 1/6, -1/3, 1/6 -> SSres = 1/6; SStot = 14/3
    assert fit.r2 == pytest.approx(1 - (1 / 6) / (14 / 3), abs=1e-12)
    assert fit.rms_um == pytest.approx(np.sqrt((1 / 6) / 3), abs=1e-12)


def test_origin_is_kept_when_first_target_missing():
    x = np.array([205.0, 225.0, 245.0])
    fit = decouple_measurement(x, -12.0 * (x - 185.0) / 1000 + 0.5, degree=1, origin_mm=185.0)
    assert fit.k_um_per_m == pytest.approx(-12.0, abs=1e-12)
    assert fit.b_um == pytest.approx(0.5, abs=1e-12)


def test_quadratic_degree_recovers_curvature():
    x = np.arange(185.0, 446.0, 20.0)
    s = (x - 185.0) / 1000.0
    fit = decouple_measurement(x, 0.3 - 8.0 * s + 40.0 * s**2, degree=2)
    np.testing.assert_allclose(fit.coefficients, [0.3, -8.0, 40.0], atol=1e-9)
    assert fit.r2 == pytest.approx(1.0)


def test_compose_curve_is_eq7():
    # Rows (b, k): k = 10 um/m over the 0.26 m stroke adds 2.6 um; (b, k, c2) adds c2 * 0.26**2.
    curves = compose_curve([[1.0, 10.0], [0.0, -20.0]], [185.0, 445.0], origin_mm=185.0)
    np.testing.assert_allclose(curves, [[1.0, 1.0 + 2.6], [0.0, -5.2]])
    np.testing.assert_allclose(
        compose_curve([0.0, 0.0, 100.0], [185.0, 445.0], 185.0), [[0.0, 100.0 * 0.0676]]
    )


def test_rejects_too_few_positions():
    with pytest.raises(ValueError, match="at least 2 distinct positions"):
        decouple_measurement([185.0], [1.0], degree=1)


def test_exact_lines_from_raw_files_are_recovered_to_1e9(tmp_path):
    ks = {(r, m): -15.0 + 1.25 * m - 2.0 * r for r in range(2) for m in range(4)}
    bs = {(r, m): -0.8 * m + 0.3 * r for r in range(2) for m in range(4)}

    def curve(r, m, x):
        return ks[r, m] * (x - x[0]) / 1000.0 + bs[r, m]

    root = write_dataset(tmp_path / "lines", curve=curve, positions=np.arange(185.0, 446.0, 20.0))
    dataset = load_dataset(root)
    frames = [
        clean_and_assemble_run(dataset, read_run(dataset, run), DEFAULTS.cleaning).errors
        for run in dataset.run_ids
    ]
    kb, _ = decouple_table(pd.concat(frames, ignore_index=True), degree=1)
    for row in kb.itertuples():
        key = (int(row.run[1:]) - 1, row.measurement - 1)
        assert abs(row.k_um_per_m - ks[key]) < 1e-9
        assert abs(row.b_um - bs[key]) < 1e-9
