"""The thermal twin: byte-identical regeneration, calibration, seeded faults, scale, isolation.

Reference numbers (Table 1, Table 5) are typed in here from the paper, not taken from
the twin; k and b are recomputed with numpy.polyfit, not with the pipeline's code.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from helpers import REPO
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.paper.equations import PublishedModel
from thermaxis.twin import ScaleSpec, generate_dataset, generate_scale
from thermaxis.twin import model as twin_model
from thermaxis.twin.network import CONDUCTANCE_W_PER_K, NODES, discretise, simulate
from thermaxis.twin.observe import calibrated_sensors, lagged

RAW = REPO / "data" / "raw" / "twin"
TRUTH = REPO / "data" / "twin_truth"
RUNS = ("E1", "E2", "E3", "E4")

# The paper's Table 5 (k um/m, b um), typed from the article.
TABLE5_K = {
    "E1": [-9.8, -9.0, -8.8, -8.6, -8.2, -7.7, -7.5, -6.6],
    "E2": [-23.7, -22.1, -22.1, -21.7, -21.5, -20.4, -19.6, -18.7],
    "E3": [-22.9, -22.1, -21.8, -21.3, -20.5, -20.1, -18.3, -18.0],
    "E4": [-13.5, -12.8, -12.6, -11.9, -11.0, -10.0, -8.8, -7.3],
}
TABLE5_B = {
    "E1": [0.1, -1.1, -1.8, -2.3, -2.6, -2.9, -3.4, -4.0],
    "E2": [-0.2, -1.2, -1.4, -1.7, -3.2, -5.1, -6.9, -8.7],
    "E3": [0.2, -1.1, -1.8, -2.5, -2.8, -3.0, -3.4, -3.2],
    "E4": [-0.1, -1.1, -1.7, -2.5, -3.4, -4.0, -4.7, -5.5],
}
# Table 1: workshop air range per experiment (degC).
TABLE1_AMBIENT = {"E1": (30.4, 31.6), "E2": (30.1, 31.2), "E3": (27.4, 28.3), "E4": (28.8, 30.5)}


def _files(root: Path) -> dict[str, bytes]:
    return {
        p.relative_to(root).as_posix(): p.read_bytes()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def _measurements(run: str, raw: Path = RAW) -> list[pd.DataFrame]:
    frames = [
        pd.read_csv(p, parse_dates=["time"]) for p in sorted((raw / run / "errors").glob("*.csv"))
    ]
    return sorted(frames, key=lambda f: f["time"].iloc[0])


def _agrees_with_truth(raw: Path, truth: Path, runs=RUNS) -> None:
    """The raw files' lines (numpy) against the generator's noise-free truth, within the
    instrument's noise, and against the paper's Table 5 within the calibration's bounds."""
    kb = pd.read_csv(truth / "kb_truth.csv").set_index(["run", "measurement"])
    dk, db, dk_paper, db_paper = [], [], [], []
    for run in runs:
        for m, frame in enumerate(_measurements(run, raw), start=1):
            k, b, _ = _polyfit_line(frame)
            dk.append(k - kb.loc[(run, m), "k_um_per_m"])
            db.append(b - kb.loc[(run, m), "b_um"])
            dk_paper.append(k - TABLE5_K[run][m - 1])
            db_paper.append(b - TABLE5_B[run][m - 1])
    assert len(dk) == 8 * len(runs)
    assert np.abs(dk).max() <= 0.3 and np.abs(db).max() <= 0.15
    assert np.sqrt(np.mean(np.square(dk_paper))) <= 0.5 * (len(RUNS) / len(runs)) ** 0.5
    assert np.sqrt(np.mean(np.square(db_paper))) <= 0.3 * (len(RUNS) / len(runs)) ** 0.5


def _polyfit_line(frame: pd.DataFrame) -> tuple[float, float, float]:
    """k (um/m), b (um at 185 mm) and R^2 of the pass-mean curve (a target read in one pass
    keeps that reading)."""
    wide = frame.pivot(index="position_mm", columns="direction", values="error_um")
    x_m = (wide.index.to_numpy(float) - 185.0) / 1000.0
    y = wide.mean(axis=1).to_numpy()
    slope, intercept = np.polyfit(x_m, y, 1)
    fitted = slope * x_m + intercept
    r2 = 1.0 - np.sum((y - fitted) ** 2) / np.sum((y - y.mean()) ** 2)
    return float(slope), float(intercept), float(r2)


@pytest.fixture(scope="module")
def raw_lines() -> pd.DataFrame:
    rows = []
    for run in RUNS:
        for m, frame in enumerate(_measurements(run), start=1):
            k, b, r2 = _polyfit_line(frame)
            rows.append((run, m, k, b, r2, TABLE5_K[run][m - 1], TABLE5_B[run][m - 1]))
    return pd.DataFrame(rows, columns=["run", "measurement", "k", "b", "r2", "k_paper", "b_paper"])


# CALIBRATION.md reports models fitted to the twin; an SVR's libsvm solution moves in the
# last bits between processors (seen: 1.79 on the machine that committed it, 1.80 on
# another), so its numbers are compared to their printed precision, the data byte for byte.
REPORT = "CALIBRATION.md"
NUMBER = re.compile(r"-?\d+\.\d+")


def _within_printed_precision(want: str, got: str) -> bool:
    """Equal text, each decimal number within one unit of its last printed digit."""
    if NUMBER.sub("#", want) != NUMBER.sub("#", got):
        return False
    for a, b in zip(NUMBER.findall(want), NUMBER.findall(got), strict=True):
        unit = 10.0 ** -len(a.split(".")[1])
        if len(a) != len(b) or abs(float(a) - float(b)) > unit * 1.0001:
            return False
    return True


def test_generate_regenerates_the_committed_files_byte_for_byte(tmp_path):
    generate_dataset(tmp_path / "raw", tmp_path / "truth")
    _agrees_with_truth(tmp_path / "raw", tmp_path / "truth")
    for committed, fresh in ((RAW, tmp_path / "raw"), (TRUTH, tmp_path / "truth")):
        want, got = _files(committed), _files(fresh)
        assert sorted(got) == sorted(want), f"file sets differ under {committed}"
        changed = [name for name in want if want[name] != got[name] and name != REPORT]
        assert not changed, f"regenerated files differ from the committed ones: {changed[:5]}"
        if REPORT in want:
            assert _within_printed_precision(want[REPORT].decode(), got[REPORT].decode())


def test_a_reduced_twin_of_one_run_is_written_byte_for_byte_twice(tmp_path):
    from thermaxis.twin import model as mdl
    from thermaxis.twin.generate import simulate_records, write_runs

    first, second = tmp_path / "a", tmp_path / "b"
    for out in (first, second):
        out.mkdir()
        write_runs(out, simulate_records(mdl.load_params())[:1])
    assert _files(first) == _files(second)
    _agrees_with_truth(first, TRUTH, runs=("E1",))
    # And it is the committed E1, file for file.
    committed = _files(RAW)
    run_files = {name: data for name, data in _files(first).items() if name.startswith("E1/")}
    assert run_files and all(committed[name] == data for name, data in run_files.items())


def test_printed_precision_allows_a_last_digit_and_nothing_more():
    assert _within_printed_precision("| SVR | 1.79 / 3.49 |", "| SVR | 1.80 / 3.50 |")
    assert not _within_printed_precision("| SVR | 1.79 |", "| SVR | 1.81 |")
    assert not _within_printed_precision("| SVR | 1.79 |", "| GPR | 1.79 |")
    assert not _within_printed_precision("| SVR | 1.79 |", "| SVR | 1.790 |")


def test_calibration_rms_against_table5_from_the_raw_files(raw_lines):
    dk = raw_lines["k"] - raw_lines["k_paper"]
    db = raw_lines["b"] - raw_lines["b_paper"]
    assert len(raw_lines) == 32
    assert np.sqrt(np.mean(dk**2)) <= 0.5
    assert np.sqrt(np.mean(db**2)) <= 0.3


def test_calibration_report_states_the_figures_recomputed_here(raw_lines):
    text = (RAW / "CALIBRATION.md").read_text(encoding="utf-8")
    rms_k = np.sqrt(np.mean((raw_lines["k"] - raw_lines["k_paper"]) ** 2))
    rms_b = np.sqrt(np.mean((raw_lines["b"] - raw_lines["b_paper"]) ** 2))
    reported_k = float(
        re.search(
            r"Table 5 slope k \(twin minus paper\) \|[^|]*\|[^|]*\| ([0-9.]+) \|", text
        ).group(1)
    )
    reported_b = float(
        re.search(
            r"Table 5 intercept b \(twin minus paper\) \|[^|]*\|[^|]*\| ([0-9.]+) \|", text
        ).group(1)
    )
    assert reported_k == pytest.approx(rms_k, abs=1e-3)
    assert reported_b == pytest.approx(rms_b, abs=1e-3)
    assert (RAW / "calibration.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_error_curves_are_strongly_but_not_perfectly_linear(raw_lines):
    assert raw_lines["r2"].min() > 0.85
    assert raw_lines["r2"].max() < 0.9999
    assert raw_lines["r2"].median() > 0.95


def test_noise_free_truth_agrees_with_the_raw_files_within_instrument_noise(raw_lines):
    truth = pd.read_csv(TRUTH / "kb_truth.csv")
    merged = raw_lines.merge(truth, on=["run", "measurement"])
    assert len(merged) == 32
    assert (merged["k"] - merged["k_um_per_m"]).abs().max() <= 0.3
    # The pass mean keeps half the 0.1 um reversal error that the truth leaves out.
    assert (merged["b"] - merged["b_um"]).abs().max() <= 0.15


def test_dataset_follows_the_documented_layout():
    dataset = load_dataset(RAW)
    assert dataset.run_ids == RUNS
    assert dataset.simulated
    meta = yaml.safe_load((RAW / "dataset.yaml").read_text(encoding="utf-8"))
    assert meta["name"] == "twin" and meta["axis"]["name"] == "X"
    assert len(meta["provenance"]["description"]) > 200
    sources = {s["name"]: s for s in meta["sources"]}
    assert set(sources) == {"box", "wireless", "hmi"}
    assert 3 <= sources["hmi"]["clock_offset_s"] <= 30
    locations = {s["id"]: (s["location"], s["source"]) for s in meta["sensors"]}
    assert [f"T{i}" for i in range(1, 13)] == list(locations)
    assert locations["T6"] == ("bearing seat near motor", "box")
    assert locations["T11"][1] == "wireless" and locations["T12"][1] == "hmi"
    runs = pd.read_csv(RAW / "runs.tsv", sep="\t")
    assert runs["feed_mm_min"].tolist() == [2000, 4000, 6000, 8000]
    for run in RUNS:
        raw = read_run(dataset, run)
        assert len(raw.measurements) == 8


def test_ambient_spans_table1_within_0_2_degrees_and_falls_with_cooling():
    for run, (lo, hi) in TABLE1_AMBIENT.items():
        hidden = pd.read_csv(TRUTH / f"{run}_hidden.csv")
        t10 = pd.read_csv(RAW / run / "temperatures" / "box.csv")["T10"]
        for series in (hidden["ambient"], t10):
            assert abs(series.min() - lo) <= 0.2 and abs(series.max() - hi) <= 0.2, run
        if run in ("E3", "E4"):
            late = hidden.loc[hidden["minute"] > 150, "ambient"]
            assert hidden["ambient"].max() - late.max() >= 0.5, (
                f"{run}: air does not fall with the cooling"
            )


def test_box_log_has_duplicated_rows_spikes_and_an_open_circuit():
    duplicated, spikes, open_circuit = 0, 0, 0
    for run in RUNS:
        box = pd.read_csv(RAW / run / "temperatures" / "box.csv", parse_dates=["time"])
        duplicated += int(box.duplicated().sum())
        steps = box["time"].drop_duplicates().diff().dropna().dt.total_seconds()
        assert (steps == 10).all(), f"{run}: box is not on a 10 s grid"
        values = box.drop(columns="time").drop_duplicates()
        open_circuit += int((values > 120).to_numpy().sum())
        plausible = values.where(values < 120)
        neighbours = 0.5 * (plausible.shift(1) + plausible.shift(-1))
        spikes += int(((plausible - neighbours).abs() > 2.0).to_numpy().sum())
    assert duplicated >= 2
    assert open_circuit == 1
    assert spikes >= 3


def test_wireless_nut_sensor_is_irregular_with_losses_and_one_long_outage():
    longest = {}
    for run in RUNS:
        log = pd.read_csv(RAW / run / "temperatures" / "wireless.csv", parse_dates=["time"])
        steps = log["time"].diff().dropna().dt.total_seconds()
        assert 25 <= steps.median() <= 35, run
        assert steps.std() > 1.0, f"{run}: wireless packets are not irregular"
        longest[run] = steps.max()
    # Lost packets leave 60-90 s holes; one outage lasts several minutes.
    assert sum(gap >= 5 * 60 for gap in longest.values()) == 1
    assert sum(gap >= 55 for gap in longest.values()) >= 3


def test_hmi_motor_sensor_is_per_minute_and_quantised_to_0_1():
    for run in RUNS:
        log = pd.read_csv(RAW / run / "temperatures" / "hmi.csv", parse_dates=["time"])
        steps = log["time"].diff().dropna().dt.total_seconds()
        assert (steps == 60).all()
        tenths = log["T12"].to_numpy() * 10.0
        assert np.allclose(tenths, np.round(tenths), atol=1e-9)


def test_one_measurement_misses_one_target_reading():
    incomplete = []
    for run in RUNS:
        for m, frame in enumerate(_measurements(run), start=1):
            per_pass = frame.groupby("direction")["position_mm"].apply(set)
            assert set(per_pass.index) == {"+", "-"}
            if len(frame) != 28:
                incomplete.append((run, m, per_pass["-"] ^ per_pass["+"]))
    assert len(incomplete) == 1
    assert len(incomplete[0][2]) == 1


def test_lag_is_exact_for_a_ramp():
    tau, step = 60.0, 10.0
    t = np.arange(0.0, 600.0 + step, step)
    got = lagged(0.01 * t, step, tau)
    # Analytic response of a first-order lag to a ramp from equilibrium.
    want = 0.01 * (t - tau * (1.0 - np.exp(-t / tau)))
    assert np.allclose(got, want, atol=1e-12)


def test_lag_acts_on_every_column_of_a_table_of_ramps():
    tau, step = 45.0, 10.0
    t = np.arange(0.0, 600.0 + step, step)
    slopes = np.array([0.01, -0.02, 0.0])
    got = lagged(20.0 + t[:, None] * slopes, step, tau)
    want = 20.0 + (t - tau * (1.0 - np.exp(-t / tau)))[:, None] * slopes
    assert np.allclose(got, want, atol=1e-12)


def test_mounting_keeps_the_clamped_part_s_share_and_splits_the_rest_by_softmax():
    values = {name: p.prior for name, p in twin_model.GLOBAL_PARAMETERS.items()}
    # T7: 60 % motor; the other 40 % split 1 : 3 between bearing seat and air.
    values.update(
        {
            "mount_T7_share": 0.6,
            "mount_T7_bearing_seat": float(np.log(1.0 / 3.0)),
            "mount_T7_ambient": 0.0,
        }
    )
    weights, _ = twin_model.mounting(values, "T7")
    assert weights == pytest.approx({"motor": 0.6, "bearing_seat": 0.1, "ambient": 0.3})
    # T12 has one neighbour: it takes all that the motor leaves.
    values.update({"mount_T12_share": 0.75, "offset_T12_C": -0.2})
    weights, offset = twin_model.mounting(values, "T12")
    assert weights == pytest.approx({"motor": 0.75, "ambient": 0.25}) and offset == -0.2
    sensor = next(s for s in calibrated_sensors(values) if s.id == "T12")
    assert (
        sensor.weights == pytest.approx({"motor": 0.75, "ambient": 0.25})
        and sensor.offset_c == -0.2
    )
    # Every sensor is calibrated; at the priors T8 reads its design: 95 % bed core, the
    # rest split e^-4 : e^-4 : 1 between the bed's walls, the carriages and the air.
    rest = 0.05 / (1.0 + 2.0 * np.exp(-4.0))
    assert next(s for s in calibrated_sensors(values) if s.id == "T8").weights == pytest.approx(
        {
            "bed_inner": 0.95,
            "bed_outer": rest * np.exp(-4.0),
            "sliders": rest * np.exp(-4.0),
            "ambient": rest,
        }
    )
    assert twin_model.GLOBAL_PARAMETERS["mount_T1_share"].lower == 0.5


def test_published_model_uses_absolute_or_run_relative_temperatures():
    temps = {"T1": np.array([30.0, 30.5, 31.0]), "T2": np.array([28.0, 28.0, 29.0])}
    absolute = PublishedModel(const=-10.0, coef={"T1": 2.0, "T2": -1.0}, relative=False)
    relative = PublishedModel(const=-10.0, coef={"T1": 2.0, "T2": -1.0}, relative=True)
    # -10 + 2*30 - 28 = 22; -10 + 61 - 28 = 23; -10 + 62 - 29 = 23
    assert absolute.predict(temps) == pytest.approx([22.0, 23.0, 23.0])
    # -10 + 0; -10 + 2*0.5; -10 + 2*1 - 1
    assert relative.predict(temps) == pytest.approx([-10.0, -9.0, -9.0])


def test_network_steady_state_balances_the_heat_input():
    disc = discretise(10.0)
    n = len(NODES)
    u = np.zeros(1 + n)
    u[0] = 25.0
    u[1 + NODES.index("nut")] = 12.0  # W
    # Fixed point of one exact step = the continuous steady state.
    final = np.linalg.solve(np.eye(n) - disc.Ad, disc.Bd @ u)
    # Steady state: all 12 W leave through the conductances to the air.
    to_air = sum(
        g * (final[NODES.index(a)] - 25.0)
        for (a, b), g in CONDUCTANCE_W_PER_K.items()
        if b == "ambient"
    )
    assert to_air == pytest.approx(12.0, rel=1e-9)
    assert (final > 25.0).all()
    # Without heat every node relaxes to the air.
    cold = simulate(disc, np.full(n, 30.0), np.tile(np.r_[25.0, np.zeros(n)], (50000, 1)))[-1]
    assert np.allclose(cold, 25.0, atol=1e-6)


def test_scale_generator_writes_the_requested_shape(tmp_path):
    spec = ScaleSpec(runs=2, sensors=5, positions=4, hours=0.5, rate_hz=0.2, seed=3, name="r2")
    generate_scale(tmp_path, spec)
    dataset = load_dataset(tmp_path)
    assert dataset.name == "r2" and dataset.run_ids == ("S001", "S002")
    assert dataset.sensors == ("T1", "T2", "T3", "T4", "T5")
    for run in dataset.run_ids:
        box = pd.read_csv(tmp_path / run / "temperatures" / "box.csv")
        assert list(box.columns) == ["time", "T1", "T2", "T3", "T4", "T5"]
        assert len(box) == 0.5 * 3600 * 0.2
        raw = read_run(dataset, run)
        assert len(raw.measurements) >= 1
        for frame in raw.measurements.values():
            assert len(frame) == 2 * 4
            assert sorted(frame["position_mm"].unique()) == [185.0, 271.667, 358.333, 445.0]


def test_scale_generator_rejects_an_impossible_shape(tmp_path):
    with pytest.raises(ValueError, match="positions"):
        generate_scale(tmp_path, ScaleSpec(runs=1, sensors=2, positions=0, hours=1.0, rate_hz=1.0))
    with pytest.raises(ValueError, match="too short"):
        generate_scale(tmp_path, ScaleSpec(runs=1, sensors=2, positions=4, hours=0.05, rate_hz=1.0))
    # A name is a results folder: never a path out of results/.
    with pytest.raises(ValueError, match="'../x' is not a safe name"):
        generate_scale(tmp_path, ScaleSpec(1, 2, 4, 1.0, 1.0, name="../x"))
    assert not any(tmp_path.iterdir())


def test_scale_generator_writes_a_single_position_at_its_measurement_period(tmp_path):
    # 1 h log, first measurement 300 s after its start, one every 600 s, each 2 readings
    # 6 s apart (both directions), so starts at 300, 900, ..., 3300 s: 6 measurements.
    spec = ScaleSpec(
        runs=1, sensors=3, positions=1, hours=1.0, rate_hz=0.1, measurement_period_s=600.0
    )
    generate_scale(tmp_path, spec)
    raw = read_run(load_dataset(tmp_path), "S001")
    assert len(raw.measurements) == 6
    for frame in raw.measurements.values():
        assert len(frame) == 2 and set(frame["position_mm"]) == {185.0}
    assert "measurements every 10 min" in (tmp_path / "dataset.yaml").read_text()


def test_no_modelling_code_reads_the_ground_truth():
    roots = [REPO / "src" / "thermaxis", REPO / "workflow", REPO / "notebooks"]
    twin_module = REPO / "src" / "thermaxis" / "twin"
    offenders = []
    for root in roots:
        for path in sorted(root.rglob("*")):
            if not path.is_file() or twin_module in path.parents or path.suffix in {".pyc", ".png"}:
                continue
            if "twin_truth" in path.read_text(encoding="utf-8", errors="ignore"):
                offenders.append(str(path.relative_to(REPO)))
    assert not offenders, f"modelling code mentions the twin's ground truth: {offenders}"


def test_the_faithfulness_block_of_docs_datasets_states_table5_as_recomputed_here(raw_lines):
    # The block is copied from the workflow's faithfulness.csv; its Table 5 rows must be
    # the RMS differences of the committed raw files, recomputed here with numpy.
    text = (REPO / "docs" / "datasets.md").read_text(encoding="utf-8")
    block = text.split("<!-- results:begin faithfulness twin -->", 1)[1].split(
        "<!-- results:end -->", 1
    )[0]
    rows = {
        cells[0]: cells
        for line in block.splitlines()
        if line.startswith("| Table 5")
        for cells in [[c.strip() for c in line.strip("|").split("|")]]
    }
    for quantity in ("k", "b"):
        (cells,) = [c for name, c in rows.items() if name.startswith(f"Table 5: {quantity}")]
        rms = np.sqrt(np.mean((raw_lines[quantity] - raw_lines[f"{quantity}_paper"]) ** 2))
        assert float(cells[2]) == pytest.approx(rms, abs=1.5e-3)
        assert cells[4] == ("yes" if rms <= {"k": 0.5, "b": 0.3}[quantity] else "no")
