"""Tables the workflow wrote read back with their run, fold and sensor labels as text."""

from __future__ import annotations

import pandas as pd

from thermaxis.reports.html import load_table
from thermaxis.sweep.run import read_sweep_table
from thermaxis.tables import read_table

CSV = "fold,run,sensor,term,rmse\n01,01,007,3,0.5\n10,10,12,T1,1.25\n"


def test_labels_stay_text_and_numbers_stay_numbers(tmp_path):
    path = tmp_path / "metrics.csv"
    path.write_text(CSV)
    for reader in (read_table, load_table):
        table = reader(path)
        # pandas alone: fold 1 and 10, sensor 7, term 3 -- labels that match no run or sensor.
        assert table["fold"].tolist() == ["01", "10"]
        assert table["run"].tolist() == ["01", "10"]
        assert table["sensor"].tolist() == ["007", "12"]
        assert table["term"].tolist() == ["3", "T1"]
        assert table["rmse"].tolist() == [0.5, 1.25]
    assert pd.read_csv(path)["fold"].tolist() == [1, 10]


def test_a_sweep_table_keeps_its_labels_and_its_integer_factors(tmp_path):
    path = tmp_path / "summary.csv"
    path.write_text("config_id,fold,n_clusters,degree,sensors,main_config\nc,02,3,,k=01+02,True\n")
    table = read_sweep_table(path)
    assert table["fold"].tolist() == ["02"]
    assert table["main_config"].tolist() == [True]  # a flag, not a label
    assert str(table["n_clusters"].dtype) == "Int64" and table["n_clusters"].tolist() == [3]
    assert table["degree"].isna().all()
