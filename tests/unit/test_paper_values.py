"""The transcribed paper values (thermaxis/paper/values/) against the paper itself.

The expected numbers are parsed here, independently of the CSV files, from verbatim excerpts
of the two texts in ``shared/paper/`` kept in ``tests/data/paper/``: the digest's markdown
tables and formulas, and the full text's own tables (the full text rules where they differ).
Where ``shared/paper`` sits beside the repository, the excerpts are checked line by line
against it and its SHA-256.
"""

from __future__ import annotations

import hashlib
import re
from collections import Counter
from pathlib import Path

import pandas as pd
import pytest

from thermaxis.paper import published

REPO_ROOT = Path(__file__).resolve().parents[2]
SHARED_PAPER = REPO_ROOT.parent / "shared" / "paper"
EXCERPTS = REPO_ROOT / "tests" / "data" / "paper"
DIGEST = EXCERPTS / "DIGEST.excerpt.md"
FULL_TEXT = EXCERPTS / "full_text.excerpt.txt"
# excerpt -> (source in shared/paper, the source's SHA-256), as in tests/data/paper/README.md.
SOURCES = {
    DIGEST: ("DIGEST.md", "998a79208b6cd7bbea6262ee0e2c87281cda3c494187f9b0e4e2ac562c31370d"),
    FULL_TEXT: (
        "000_298bf3df7931147d.txt",
        "298bf3df7931147d372cf43706ebff11bd81c7c7f7c59958ab65ab8555cc3714",
    ),
}

RUNS = ("E1", "E2", "E3", "E4")
TARGET_WORDS = {"斜率": "k", "截距": "b", "热定位误差": "error"}


# ----------------------------------------------------------------------------- parsing helpers
def _num(text: str) -> float:
    """A number as printed: unicode minus and OCR spaces inside the number allowed."""
    return float(text.replace("−", "-").replace(" ", ""))


def _digest_table(heading: str) -> list[list[str]]:
    """Body rows (cells stripped) of the first markdown table after a line starting with heading."""
    lines = DIGEST.read_text(encoding="utf-8").splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(heading))
    rows, seen_table = [], False
    for line in lines[start + 1 :]:
        if line.startswith("|"):
            seen_table = True
            rows.append([cell.strip() for cell in line.strip().strip("|").split("|")])
        elif seen_table:
            break
    return [r for r in rows[1:] if not set("".join(r)) <= set("-")]  # drop header and |---|


def _digest_paragraph(start: str, stop: str) -> str:
    text = DIGEST.read_text(encoding="utf-8")
    begin = text.index(start)
    return " ".join(text[begin : text.index(stop, begin)].split())


def _linear_terms(expression: str) -> dict[str, float]:
    """Coefficients of 'c0 ± c1·Ta ± c2·(Tb − Tb⁰) …' (digest notation), keyed const / sensor."""
    terms = {}
    for sign, value, sensor in re.findall(r"([+−-]?)\s*(\d+\.\d+)(?:·\(?(T\d+))?", expression):
        terms[sensor or "const"] = -float(value) if sign in ("−", "-") else float(value)
    return terms


def _latex_terms(expression: str) -> dict[str, float]:
    """Coefficients of the full text's LaTeX form, e.g. '-0.\\ 421 - 7.\\ 417 \\cdot T_1 …'."""
    # Line breaks ("\\\\") first: their second backslash would otherwise pass for the
    # OCR's "\\ " inside split decimals.
    flat = expression.replace("\\\\", " ").replace("\\ ", "")
    terms = {}
    pattern = r"([+-]?)\s*(\d+\.\d+)\s*(?:\\cdot\s*\(?\s*T_\{?(\d+)\}?)?"
    for sign, value, sensor in re.findall(pattern, flat):
        terms[f"T{sensor}" if sensor else "const"] = -float(value) if sign == "-" else float(value)
    return terms


def _full_text() -> str:
    return FULL_TEXT.read_text(encoding="utf-8")


def _sensor_key(sensor: str) -> int:
    return int(sensor[1:])


# ----------------------------------------------------------------------------- the excerpts
@pytest.mark.skipif(
    not SHARED_PAPER.is_dir(),
    reason=f"the paper's texts are not at {SHARED_PAPER}: the excerpts are not traced to them",
)
@pytest.mark.parametrize("excerpt", list(SOURCES), ids=lambda p: p.name)
def test_the_excerpts_are_lines_of_the_paper_in_order(excerpt):
    name, sha256 = SOURCES[excerpt]
    source = (SHARED_PAPER / name).read_bytes()
    assert hashlib.sha256(source).hexdigest() == sha256
    lines = iter(source.decode("utf-8").splitlines())
    missing = [line for line in excerpt.read_text(encoding="utf-8").splitlines()
               if not any(line == other for other in lines)]  # fmt: skip
    assert missing == []


# ----------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def values() -> pd.DataFrame:
    return published.published_values().set_index("item")


# ----------------------------------------------------------------------------- Table 1
def test_table1_matches_digest_and_full_text():
    table = published.load_table("table1").set_index("experiment")
    digest_rows = _digest_table("Table 1")
    assert len(digest_rows) == 4
    for experiment, feed, measurements, ambient in digest_rows:
        low, high = ambient.split("–")
        row = table.loc[int(experiment)]
        assert (row.feed_mm_min, row.measurements) == (float(feed), int(measurements))
        assert (row.ambient_min_c, row.ambient_max_c) == (_num(low), _num(high))
        assert row.run == f"E{experiment}"

    text = _full_text()
    block = " ".join(text[text.index("实验次数") : text.index("温度测量方面")].split())
    printed = re.findall(r"\b([1-4]) (\d) 000 (8) (\d+\. ?\d)~(\d+\. ?\d)", block)
    assert len(printed) == 4
    for experiment, thousands, _, low, high in printed:
        row = table.loc[int(experiment)]
        assert row.feed_mm_min == 1000 * int(thousands)
        assert (row.ambient_min_c, row.ambient_max_c) == (_num(low), _num(high))


# ----------------------------------------------------------------------------- Table 2
def test_table2_sensors_match_digest():
    sensors = published.load_table("table2").set_index("sensor")
    assert list(sensors.index) == [f"T{i}" for i in range(1, 13)]
    digest = {}
    for a, loc_a, b, loc_b in _digest_table("Table 2"):
        digest[a], digest[b] = loc_a, loc_b
    # The digest annotates the acquisition in parentheses; compare the location words only.
    strip = lambda s: re.sub(r"\s*\(.*\)", "", s)  # noqa: E731
    assert {s: strip(loc) for s, loc in digest.items()} == {
        s: strip(loc) for s, loc in sensors["location"].items()
    }
    assert sensors.loc["T11", "acquisition"] == "wireless"
    assert sensors.loc["T12", "acquisition"] == "hmi"
    assert set(sensors.loc[[f"T{i}" for i in range(1, 11)], "acquisition"]) == {"box"}


# ----------------------------------------------------------------------------- Table 3
def _table3_sets() -> dict[int, set[str]]:
    df = published.load_table("table3")
    return {int(p): set(g["sensor"]) for p, g in df.groupby("position_mm")}


def test_table3_matches_digest_and_full_text():
    digest = {}
    for p1, s1, p2, s2 in _digest_table("Table 3"):
        digest[int(p1)], digest[int(p2)] = set(s1.split(",")), set(s2.split(","))
    full = {int(p): set(s.split(",")) for p, s in re.findall(r"(\d{3})\t\{([^}]*)\}", _full_text())}
    assert digest == full
    assert _table3_sets() == digest


def test_table3_has_three_points_at_each_of_the_14_targets():
    sets = _table3_sets()
    assert sorted(sets) == list(range(185, 446, 20))
    assert all(len(s) == 3 for s in sets.values())


def test_table3_three_most_frequent_points_are_the_eq8_inputs():
    # The paper picks the three points found most often in Table 3 as Eq. 8's inputs.
    counts = Counter(published.load_table("table3")["sensor"])
    top3 = {sensor for sensor, _ in counts.most_common(3)}
    assert counts.most_common(4)[2][1] > counts.most_common(4)[3][1]  # no tie at rank 3
    eq8_sensors = set(published.load_table("eq8")["term"]) - {"const"}
    assert top3 == eq8_sensors == {"T1", "T11", "T12"}


# ----------------------------------------------------------------------------- Table 5
def _digest_table5() -> dict[tuple[str, int, str], float]:
    expected = {}
    for cells in _digest_table("Table 5"):
        measurement = int(cells[0])
        for i, run in enumerate(RUNS):
            expected[(run, measurement, "k")] = _num(cells[1 + 2 * i])
            expected[(run, measurement, "b")] = _num(cells[2 + 2 * i])
    return expected


def test_table5_all_64_numbers_match_digest(values):
    expected = _digest_table5()
    assert len(expected) == 64
    table = published.load_table("table5").set_index(["run", "measurement"])
    for (run, m, target), value in expected.items():
        column = "k_um_per_m" if target == "k" else "b_um"
        assert table.loc[(run, m), column] == value, (run, m, target)
        assert values.loc[f"table5/{run}/m{m}/{target}", "value"] == value


def test_table5_digest_agrees_with_full_text():
    printed = re.findall(r"^([1-8])((?:[ \t]+-?\d+\.\d){8})\s*$", _full_text(), re.M)
    assert len(printed) == 8
    full = {}
    for measurement, numbers in printed:
        cells = numbers.split()
        for i, run in enumerate(RUNS):
            full[(run, int(measurement), "k")] = float(cells[2 * i])
            full[(run, int(measurement), "b")] = float(cells[2 * i + 1])
    assert full == _digest_table5()


def test_table5_shape_and_keys():
    table = published.load_table("table5")
    assert len(table) == 32
    assert not table.duplicated(["run", "measurement"]).any()
    assert (table["k_um_per_m"] < 0).all()  # every printed slope is negative


# ----------------------------------------------------------------------------- Table 6
def _parse_clusters(cell: str) -> list[set[str]]:
    return [set(c.split(",")) for c in re.findall(r"\{([^}]*)\}", cell.replace(" ", ""))]


def test_table6_matches_digest_and_full_text():
    table = published.load_table("table6")
    ours = {
        target: (
            [set(g["sensor"]) for _, g in sub.groupby("cluster")],
            set(sub.loc[sub["selected"], "sensor"]),
        )
        for target, sub in table.groupby("target")
    }
    digest = {
        t: (_parse_clusters(c), set(p.replace(" ", "").split(",")))
        for t, c, p in _digest_table("Table 6")
    }
    full = {
        t: (_parse_clusters(c), set(p.split(",")))
        for t, c, p in re.findall(r"^([kb])\t(.*?)\t(T[\d,T]+)\s*$", _full_text(), re.M)
    }
    assert digest == full
    assert ours == digest


def test_table6_one_sensitive_point_per_cluster_and_they_are_the_eq9_inputs():
    table = published.load_table("table6")
    assert (table.groupby(["target", "cluster"])["selected"].sum() == 1).all()
    eq9 = published.load_table("eq9")
    for target in ("k", "b"):
        selected = set(table.loc[table["selected"] & (table["target"] == target), "sensor"])
        inputs = set(eq9.loc[(eq9["target"] == target) & (eq9["term"] != "const"), "term"])
        assert selected == inputs


def test_table6_clusters_are_numbered_by_their_lowest_sensor():
    table = published.load_table("table6")
    for _, sub in table.groupby("target"):
        lowest = sub.groupby("cluster")["sensor"].agg(lambda s: min(map(_sensor_key, s)))
        assert list(lowest.sort_index()) == sorted(lowest)


# ----------------------------------------------------------------------------- Tables 4, 7, 8
_DIGEST_MODELS = {
    "point-by-point MLR": ("pointwise", "mlr"),
    "decoupled MLR": ("decoupled", "mlr"),
    "decoupled SVR": ("decoupled", "svr"),
}


def test_prediction_metrics_match_digest(values):
    rows = _digest_table("Prediction of experiment 4")
    assert len(rows) == 7
    table = published.load_table("prediction_metrics").set_index(["table", "target"])
    for number, model, target_cell, rmse, max_abs, mae in rows:
        target = target_cell.split()[0]
        row = table.loc[(int(number), target)]
        assert (row.approach, row.algorithm) == _DIGEST_MODELS[model]
        assert (row.rmse, row.max_abs, row.mae) == (float(rmse), float(max_abs), float(mae))
        assert values.loc[f"table{number}/{target}/max_abs", "value"] == float(max_abs)
    assert len(table) == 7


def test_prediction_metrics_match_full_text_tables():
    printed, current_table = {}, None
    for line in _full_text().splitlines():
        heading = re.match(r"^表\s*(\d)\b", line)
        if heading:
            current_table = int(heading.group(1))
        cells = line.split("\t")
        word = next((w for w in TARGET_WORDS if cells[0].startswith(w)), None)
        if word and len(cells) == 4:
            printed[(current_table, TARGET_WORDS[word])] = tuple(map(float, cells[1:]))
    table = published.load_table("prediction_metrics")
    ours = {(r.table, r.target): (r.rmse, r.max_abs, r.mae) for r in table.itertuples()}
    assert ours == printed


def test_residual_ranges_and_largest_error_match_digest(values):
    text = _digest_paragraph("Residual ranges of the error", "Figures:")
    mlr = re.search(r"MLR (−?\d+\.\d) … (−?\d+\.\d) µm", text)
    svr = re.search(r"SVR (−?\d+\.\d) … (−?\d+\.\d) µm", text)
    largest = re.search(r"largest thermal positioning error is (\d+\.\d) µm", text)
    assert values.loc["text/decoupled_mlr/error/residual_min", "value"] == _num(mlr.group(1))
    assert values.loc["text/decoupled_mlr/error/residual_max", "value"] == _num(mlr.group(2))
    assert values.loc["text/decoupled_svr/error/residual_min", "value"] == _num(svr.group(1))
    assert values.loc["text/decoupled_svr/error/residual_max", "value"] == _num(svr.group(2))
    assert values.loc["text/measured/error/max_abs_error", "value"] == float(largest.group(1))


def test_residual_ranges_are_consistent_with_the_max_abs_residuals():
    # The printed max |residual| of the error must be the larger end of the printed range.
    ranges = published.load_table("residual_ranges")
    metrics = published.load_table("prediction_metrics").set_index(["table", "target"])
    for r in ranges.itertuples():
        assert max(-r.residual_min, r.residual_max) == metrics.loc[(r.table, r.target), "max_abs"]


def test_slope_induced_error_is_the_max_slope_residual_over_the_stroke(values):
    k_max = values.loc["table7/k/max_abs", "value"]  # um/m
    stroke_m = (445 - 185) / 1000
    assert values.loc[
        "text/decoupled_mlr/error/max_error_from_k_residual", "value"
    ] == pytest.approx(k_max * stroke_m, abs=0.005)


# ----------------------------------------------------------------------------- Eq. 8, Eq. 9
def test_eq8_matches_digest_and_full_text(values):
    digest_text = _digest_paragraph("Eq. 8", "3. Decoupling")
    parts = re.split(r"dx(\d+) =", digest_text)[1:]
    digest = {
        int(row): _linear_terms(expr.split(";")[0])
        for row, expr in zip(parts[::2], parts[1::2], strict=True)
    }
    assert sorted(digest) == [1, 2, 3, 14]

    line = next(row for row in _full_text().splitlines() if "dx_1 =" in row)
    full_parts = re.split(r"dx_\{?(\d+)\}? =", line.split("(8)")[0] + line.split("\\vdots")[1])[1:]
    full = {
        int(row): _latex_terms(expr)
        for row, expr in zip(full_parts[::2], full_parts[1::2], strict=True)
    }
    assert full == digest

    eq8 = published.load_table("eq8")
    ours = {
        int(row): dict(zip(g["term"], g["value"], strict=True))
        for row, g in eq8.groupby("equation_row")
    }
    assert ours == digest
    for row, group in eq8.groupby("equation_row"):
        assert set(group["position_mm"]) == {185 + 20 * (row - 1)}
    assert values.loc["eq8/dx14/T11", "value"] == digest[14]["T11"]


def test_eq9_matches_digest_and_full_text(values):
    digest_text = _digest_paragraph("Eq. 9 (MLR):", "5. Train")
    k_expr, b_expr = re.split(r"\bb =", digest_text.split("k =", 1)[1])
    digest = {"k": _linear_terms(k_expr), "b": _linear_terms(b_expr)}
    assert set(digest["k"]) == {"const", "T1", "T6", "T12"}
    assert set(digest["b"]) == {"const", "T2", "T7", "T11"}

    line = next(row for row in _full_text().splitlines() if "k = -306" in row)
    full_k, full_b = line.split("b =")
    assert {"k": _latex_terms(full_k.split("k =")[1]), "b": _latex_terms(full_b)} == digest

    eq9 = published.load_table("eq9")
    for target, terms in digest.items():
        sub = eq9[eq9["target"] == target]
        assert dict(zip(sub["term"], sub["value"], strict=True)) == terms
        for term, value in terms.items():
            assert values.loc[f"eq9/{target}/{term}", "value"] == value
    assert set(eq9.loc[eq9["target"] == "k", "temperature"]) == {"absolute"}
    assert set(eq9.loc[eq9["target"] == "b", "temperature"]) == {"relative"}


# ----------------------------------------------------------------------------- published_values()
def test_published_values_shape_and_unique_keys(values):
    frame = published.published_values()
    assert tuple(frame.columns) == published.PUBLISHED_COLUMNS
    assert frame["item"].is_unique
    assert frame["value"].notna().all() and frame["unit"].notna().all()
    # Counts follow from the paper's layout: 4 runs x 4 numbers; 14 positions x 3 points;
    # 3 metrics; 32 measurements x (k, b); 11 + 12 clustered sensors + 2 x 3 points;
    # 3 targets x 3 metrics (twice); 4 printed rows x 4 terms; 2 x 4 terms; 7 text numbers.
    expected = {
        "table1": 16,
        "table3": 42,
        "table4": 3,
        "table5": 64,
        "table6": 29,
        "table7": 9,
        "table8": 9,
        "eq8": 16,
        "eq9": 8,
        "text": 7,
    }
    assert frame["table"].value_counts().to_dict() == expected
    assert str(frame["measurement"].dtype) == "Int64" and str(frame["position_mm"].dtype) == "Int64"


def test_published_values_item_encodes_its_describing_columns(values):
    table5 = values[values["table"] == "table5"]
    rebuilt = (
        "table5/"
        + table5["run"]
        + "/m"
        + table5["measurement"].astype(str)
        + "/"
        + table5["target"]
    )
    assert list(rebuilt) == list(table5.index)
    assert values.loc["table3/445mm/T12", ["quantity", "value"]].tolist() == [
        "sensitive_point",
        1.0,
    ]
    assert values.loc["table6/b/T7/cluster", "value"] == 3.0
    assert "table6/k/T7/cluster" not in values.index  # T7 is in no k cluster as printed


# ----------------------------------------------------------------------------- bad input
def test_unknown_table_name_is_a_value_error():
    with pytest.raises(ValueError, match="unknown paper table 'table9'"):
        published.load_table("table9")


def test_renamed_column_is_a_value_error(tmp_path):
    source = published.PAPER_DIR / "table5_slope_intercept.csv"
    text = source.read_text(encoding="utf-8").replace("k_um_per_m", "k")
    (tmp_path / source.name).write_text(text, encoding="utf-8")
    with pytest.raises(ValueError, match="do not match the expected"):
        published.load_table("table5", paper_dir=tmp_path)


def test_paper_dir_is_overridable(tmp_path):
    source = published.PAPER_DIR / "eq9_decoupled_mlr.csv"
    edited = source.read_text(encoding="utf-8").replace("-306.494", "-1.5")
    (tmp_path / source.name).write_text(edited, encoding="utf-8")
    eq9 = published.load_table("eq9_decoupled_mlr.csv", paper_dir=tmp_path)
    assert eq9.loc[(eq9["target"] == "k") & (eq9["term"] == "const"), "value"].item() == -1.5


def test_the_twins_table5_is_the_transcription_read_with_the_csv_module():
    # The twin's calibration targets are the 64 numbers of table5_slope_intercept.csv,
    # here parsed with the csv module and float(), apart from the package's reader.
    import csv

    from thermaxis.twin.problem import paper_table5

    with open(published.PAPER_DIR / "table5_slope_intercept.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    expected: dict[str, list[tuple[int, float, float]]] = {}
    for row in rows:
        expected.setdefault(row["run"], []).append(
            (int(row["measurement"]), float(row["k_um_per_m"]), float(row["b_um"]))
        )
    table5 = paper_table5()
    assert list(table5) == sorted(expected) == list(RUNS)
    for run, measurements in expected.items():
        measurements.sort()
        assert [m for m, _, _ in measurements] == list(range(1, 9))
        # Exact: both sides parse the same decimal strings to the nearest double.
        assert table5[run] == (
            tuple(k for _, k, _ in measurements),
            tuple(b for _, _, b in measurements),
        )
    assert sum(len(k) + len(b) for k, b in table5.values()) == 64
