"""Assembly: unzeroed vs re-zeroed errors, measurement temperatures, the estimators' view."""

import numpy as np
import pandas as pd

from thermaxis.cleaning.run import model_inputs, tidy_errors, tidy_temperatures
from thermaxis.labels import natural_key


def windows(n=3):
    t0 = pd.Timestamp("2022-05-10T09:00:00")
    return pd.DataFrame(
        {
            "measurement": range(1, n + 1),
            "start": [t0 + pd.Timedelta(minutes=23 * i) for i in range(n)],
            "end": [t0 + pd.Timedelta(minutes=23 * i + 2) for i in range(n)],
        }
    )


def test_rezeroed_is_each_measurement_minus_its_own_first_reading():
    curves = [
        pd.Series([0.0, -1.0, -2.0], index=[185.0, 205.0, 225.0]),
        pd.Series([-1.5, -2.0, np.nan], index=[185.0, 205.0, 225.0]),
    ]
    e = tidy_errors("E1", 1, windows(2), curves)
    assert e["error_um"].tolist()[:5] == [0.0, -1.0, -2.0, -1.5, -2.0]
    assert e["rezeroed_um"].tolist()[:5] == [0.0, -1.0, -2.0, 0.0, -0.5]
    assert np.isnan(e["rezeroed_um"].iloc[5])
    assert e["time_min"].tolist() == [0.0] * 3 + [23.0] * 3


def test_relative_temperatures_start_at_zero():
    temps = pd.DataFrame({"T2": [20.0, 21.5, 22.0], "T10": [30.0, 29.0, 28.5]})
    t = tidy_temperatures("E3", 3, windows(), temps)
    rel = t.pivot(index="measurement", columns="sensor", values="relative_c")
    assert rel.loc[1].tolist() == [0.0, 0.0]
    assert rel.loc[3, "T2"] == 2.0 and rel.loc[3, "T10"] == -1.5


def test_model_inputs_align_rows_and_order_sensors_naturally():
    curves = [pd.Series([0.0, 1.0], index=[0.0, 100.0]) for _ in range(3)]
    errors = tidy_errors("R", 1, windows(), curves)
    temps = tidy_temperatures(
        "R", 1, windows(), pd.DataFrame({"T10": [1.0, 2, 3], "T2": [4.0, 5, 6], "T1": [7.0, 8, 9]})
    )
    X, Y = model_inputs(errors, temps)
    assert list(X.columns) == ["run", "measurement", "time_min", "T1", "T2", "T10"]
    assert list(Y.columns) == [0.0, 100.0]
    assert X["T10"].tolist() == [1.0, 2.0, 3.0]
    assert sorted(["T12", "T9", "T1"], key=natural_key) == ["T1", "T9", "T12"]
