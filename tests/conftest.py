"""Shared test helpers: tiny datasets in the documented raw layout, written from known truth."""

from __future__ import annotations

import fcntl
import os
import re
import subprocess
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from thermaxis.config import Settings

REPO = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
# 2023-11-14T22:13:20Z: pins the run time recorded in provenance and reports, the one
# field that is otherwise meant to differ between runs.
FIXED_EPOCH = "1700000000"
# Every stage's settings from an empty config: the schema's defaults, through the config
# loader (the settings dataclasses have no defaults of their own).
DEFAULTS = Settings.from_config({})


def workflow_workdir(tmp_path: Path) -> Path:
    """A scratch copy of the workflow's entry points (symlinks), so results stay in tmp."""
    work = tmp_path / "work"
    (work / "data").mkdir(parents=True)
    for name in ("Snakefile", "config", "workflow", "notebooks"):
        os.symlink(REPO / name, work / name)
    return work


def snakemake_env() -> dict:
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONHASHSEED": "0", "SOURCE_DATE_EPOCH": FIXED_EPOCH}
    env["PATH"] = f"{Path(sys.executable).parent}:{env['PATH']}"
    return env


def run_snakemake(work: Path, *args, check=True, env=None, timeout=900) -> subprocess.CompletedProcess:
    proc = subprocess.run(
        [SNAKEMAKE, "--cores", "2", "--nolock", *args],
        cwd=work,
        capture_output=True,
        text=True,
        env=env or snakemake_env(),
        timeout=timeout,
    )
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-5000:]}")
    return proc


def set_csv_cell(path: Path, line: int, field: int, value: str) -> None:
    """Overwrite one cell of a CSV file (``line`` is the 0-based line index, header = 0)."""
    lines = Path(path).read_text().splitlines()
    fields = lines[line].split(",")
    fields[field] = value
    lines[line] = ",".join(fields)
    Path(path).write_text("\n".join(lines) + "\n")


def write_dataset(
    root: Path,
    *,
    runs=("R1", "R2"),
    sensors=("S1", "S2", "S3"),
    positions=(0.0, 50.0, 100.0, 150.0),
    n_measurements=4,
    interval_min=20.0,
    curve=None,
    temperature=None,
    name="tiny",
    kind="simulated",
    two_passes=True,
    reproduces=None,
) -> Path:
    """Write a small, fault-free dataset.

    ``n_measurements`` is one count for every run, or one count per run (runs of
    unequal length).  ``curve(run_index, measurement_index, positions) -> errors`` gives the error of
    each measurement; ``temperature(run_index, sensor_index, minutes) -> degC`` the
    sensor logs (sampled every 10 s). Defaults: exact lines and smooth ramps.
    """
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    positions = np.asarray(positions, dtype=float)
    if curve is None:
        def curve(r, m, x):
            return (-10.0 + 0.5 * m + r) * (x - x[0]) / 1000.0 + (-0.7 * m - 0.1 * r)
    if temperature is None:
        def temperature(r, s, minutes):
            return 20.0 + r + 0.5 * s + (1.0 + 0.3 * s) * (1.0 - np.exp(-minutes / (60.0 + 10 * s)))
    meta = {
        "name": name,
        "description": "Tiny test dataset.",
        "provenance": {"kind": kind, "citation": "tests"},
        **({"reproduces": reproduces} if reproduces else {}),
        "axis": {"name": "X"},
        "sensors": [{"id": s, "location": f"loc {s}", "source": "box"} for s in sensors],
        "sources": [{"name": "box", "clock_note": "reference", "clock_offset_s": 0}],
    }
    (root / "dataset.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    lines = ["run\tcondition\tfeed_mm_min\tdescription"]
    for i, run in enumerate(runs, start=1):
        lines.append(f"{run}\t{i}\t{1000 * i}\trun {run}")
    (root / "runs.tsv").write_text("\n".join(lines) + "\n")
    t0 = pd.Timestamp("2022-05-10T09:00:00")
    counts = [n_measurements] * len(runs) if np.ndim(n_measurements) == 0 else list(n_measurements)
    for r, (run, n_run) in enumerate(zip(runs, counts)):
        total = interval_min * (n_run - 1) + 10
        (root / run / "temperatures").mkdir(parents=True, exist_ok=True)
        (root / run / "errors").mkdir(parents=True, exist_ok=True)
        seconds = np.arange(-300, total * 60 + 300, 10.0)
        frame = pd.DataFrame({"time": (t0 + pd.to_timedelta(seconds, unit="s")).strftime("%Y-%m-%dT%H:%M:%S")})
        for s, sensor in enumerate(sensors):
            frame[sensor] = temperature(r, s, seconds / 60.0)
        frame.to_csv(root / run / "temperatures" / "box.csv", index=False, float_format="%.6f")
        for m in range(n_run):
            start = t0 + pd.Timedelta(minutes=interval_min * m)
            err = curve(r, m, positions)
            rows = []
            passes = [("+", positions, err), ("-", positions[::-1], err[::-1])] if two_passes else [("+", positions, err)]
            k = 0
            for direction, xs, es in passes:
                for x, e in zip(xs, es):
                    rows.append(((start + pd.Timedelta(seconds=5 * k)).strftime("%Y-%m-%dT%H:%M:%S"), x, e, direction))
                    k += 1
            pd.DataFrame(rows, columns=["time", "position_mm", "error_um", "direction"]).to_csv(
                root / run / "errors" / f"M{m + 1:02d}.csv", index=False, float_format="%.12g"
            )
    return root


@pytest.fixture
def tiny_dataset(tmp_path):
    return write_dataset(tmp_path / "tiny")


# --------------------------------------------------------------------------- Eq. 8 and Eq. 9 by construction

POSITIONS = np.arange(185.0, 446.0, 20.0)  # the paper's 14 targets
SENSORS = [f"T{i}" for i in range(1, 13)]

# Eq. 9 as printed: k [um/m] on absolute, b [um] on relative temperatures.
EQ9_K = {"const": -306.494, "T1": 13.247, "T6": -6.629, "T12": 3.326}
EQ9_B = {"const": -0.576, "T2": -11.058, "T7": 0.974, "T11": -1.915}

# Eq. 8 prints rows 1-3 and 14; rows 4-13 are interpolated linearly between row 3 and row 14.
_EQ8_PRINTED = {
    0: (-0.421, -7.417, -2.961, 1.180),
    1: (-0.708, -7.288, -2.706, 1.066),
    2: (-1.131, -7.237, -2.548, 1.001),
    13: (-4.544, -4.908, 2.436, -1.032),
}
EQ8 = np.array(
    [
        (
            _EQ8_PRINTED[j]
            if j in _EQ8_PRINTED
            else tuple(
                np.array(_EQ8_PRINTED[2])
                + (j - 2) / 11 * (np.array(_EQ8_PRINTED[13]) - np.array(_EQ8_PRINTED[2]))
            )
        )
        for j in range(14)
    ]
)  # columns const, T1, T11, T12


def synthetic_temperatures(runs=("E1", "E2", "E3", "E4"), n_measurements=8, seed=20220510) -> pd.DataFrame:
    """Smooth warming curves plus a slow random walk per sensor, so sensors are not collinear."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_measurements) / (n_measurements - 1)
    rows = []
    for run in runs:
        base = rng.uniform(26.0, 32.0) + rng.normal(0.0, 1.0, len(SENSORS))
        rise = rng.uniform(0.5, 6.0, len(SENSORS))
        tau = rng.uniform(0.2, 1.0, len(SENSORS))
        walk = np.cumsum(rng.normal(0.0, 0.15, (n_measurements, len(SENSORS))), axis=0)
        temps = base + rise * (1.0 - np.exp(-t[:, None] / tau)) + walk
        for m in range(n_measurements):
            rows.append({"run": run, "measurement": m + 1, **dict(zip(SENSORS, temps[m]))})
    return pd.DataFrame(rows)


def eq9_truth(X: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """k and b straight from Eq. 9, relative temperatures computed here by hand."""
    k = EQ9_K["const"] + sum(c * X[s].to_numpy() for s, c in EQ9_K.items() if s != "const")
    b = np.full(len(X), EQ9_B["const"])
    for s, c in EQ9_B.items():
        if s == "const":
            continue
        first = X.loc[X["measurement"] == 1].set_index("run")[s]
        b = b + c * (X[s].to_numpy() - first.loc[X["run"]].to_numpy())
    return k, b


def eq9_errors(X: pd.DataFrame, c2=None) -> pd.DataFrame:
    k, b = eq9_truth(X)
    shifted_m = (POSITIONS - POSITIONS[0]) / 1000.0
    errors = k[:, None] * shifted_m + b[:, None]
    if c2 is not None:
        errors = errors + c2[:, None] * shifted_m**2
    return pd.DataFrame(errors, columns=POSITIONS, index=X.index)


def eq8_errors(X: pd.DataFrame) -> pd.DataFrame:
    first = X.loc[X["measurement"] == 1].set_index("run")
    rel = np.column_stack([X[s].to_numpy() - first.loc[X["run"], s].to_numpy() for s in ("T1", "T11", "T12")])
    design = np.column_stack([np.ones(len(X)), rel])
    return pd.DataFrame(design @ EQ8.T, columns=POSITIONS, index=X.index)


# --------------------------------------------------------------------------- workflow runs shared by tests

def tiny_config(work: Path, dataset: Path, name: str = "test_config.yaml", **extra) -> Path:
    """The workflow configuration of the end-to-end tests, written to ``work/name``.

    Two algorithms with a two-point SVR grid and one figure and report algorithm keep
    the runs short; the full algorithm set is exercised by the unit tests and `make results`.
    ``extra`` replaces top-level keys.
    """
    config = {
        "dataset": str(dataset),
        "ambient_sensor": "S1",
        "selection": {"n_clusters": 2},
        "models": {"algorithms": ["mlr", "svr"], "svr_grid": {"C": [1.0, 10.0], "epsilon": [0.1], "gamma": ["scale"]}},
        "figures": {"algorithms": ["mlr"]},
        "reports": {"model_algorithms": ["mlr"]},
        **extra,
    }
    path = work / name
    path.write_text(yaml.safe_dump(config))
    return path


# k and b of each (run, measurement) of the `lines` dataset: exact lines the pipeline must recover.
def k_true(r, m):
    return -10.0 + 0.5 * m + r + 0.1 * m * m


def b_true(r, m):
    return -0.7 * m - 0.1 * r + 0.05 * r * m


def exact_line(r, m, x):
    return k_true(r, m) * (x - x[0]) / 1000.0 + b_true(r, m)


LINES_RUNS = ("R1", "R2", "R3")
LINES_SENSORS = ("S1", "S2", "S3", "S4")
# The sweep grid of the `sweep` target (not part of `all`), which test_sweep_workflow runs
# on top of `lines_run`: 3 folds x (fuzzy 2 x 2 + correlation 2 = 6 selection settings)
# x (2 degrees + pointwise) x 2 algorithms.
LINES_SWEEP = {
    "methods": ["fuzzy_grey", "correlation"],
    "n_clusters": [2, 3],
    "similarity": ["pearson"],
    "grade": ["deng", "absolute"],
    "degrees": [1, 2],
    "algorithms": ["mlr", "svr"],
    "svr_grid": "models",
}


@dataclass(frozen=True)
class Run:
    work: Path
    dataset: Path
    config: Path
    out: Path


@pytest.fixture(scope="session")
def lines_run(tmp_path_factory) -> Run:
    """The whole workflow (target ``all``: tables, figures, compensation, reports) once per
    session on three runs of five measurements whose errors are exact lines.

    Tests read it or dry-run against it (`-n`); only test_sweep_workflow adds to it, the
    ``sweep/`` folder of the `sweep` target, which `all` does not make.
    """
    tmp = tmp_path_factory.mktemp("lines")
    dataset = write_dataset(tmp / "lines", runs=LINES_RUNS, sensors=LINES_SENSORS, curve=exact_line, name="lines",
                            n_measurements=5)  # fmt: skip
    work = workflow_workdir(tmp)
    # No model reports (notebooks are the costliest jobs, and this run is made twice, see
    # test_interrupted_run): the reports build `built` has them and checks their bytes.
    config = tiny_config(work, dataset, reports={"model_algorithms": []}, sweep=LINES_SWEEP)
    run_snakemake(work, "--configfile", str(config))
    return Run(work=work, dataset=dataset, config=config, out=work / "results" / "lines")


@contextmanager
def library_lock(tmp_path_factory, exclusive: bool = False):
    """A lock over the library's source files, shared by the pytest-xdist workers.

    A test that edits a module of src/thermaxis (and restores it) holds it exclusively;
    a test whose dry run must see the library as it is holds it shared.
    """
    path = tmp_path_factory.getbasetemp().parent / "thermaxis-library.lock"
    with open(path, "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


@pytest.fixture
def library_unchanged(tmp_path_factory):
    """For tests that dry-run (`-n`) and check what would rerun: no module is being edited meanwhile."""
    with library_lock(tmp_path_factory):
        yield


def planned_rules(proc: subprocess.CompletedProcess) -> set[str]:
    """Rule names a Snakemake dry run (`-n`) would run."""
    return set(re.findall(r"^(?:local)?rule (\w+):", proc.stdout + proc.stderr, flags=re.M))


# --------------------------------------------------------------------------- the reports build


@dataclass(frozen=True)
class Built:
    work: Path
    out: Path
    dataset: Path
    config: Path
    env: dict


def reports_snakemake(built: Built, *args, check=True) -> subprocess.CompletedProcess:
    return run_snakemake(built.work, "--configfile", str(built.config), *args, check=check, env=built.env)


@pytest.fixture(scope="session")
def built(tmp_path_factory) -> Built:
    """The workflow with every kind of report on a small simulated dataset that reproduces
    the paper, once per test session (the reports and the browser tests read it)."""
    tmp = tmp_path_factory.mktemp("reports")
    dataset = write_dataset(tmp / "rep", runs=("R1", "R2"), name="rep", reproduces="xu2023")
    work = workflow_workdir(tmp)
    config = work / "reports_config.yaml"
    config.write_text(
        yaml.safe_dump(
            {
                "dataset": str(dataset),
                "ambient_sensor": "S1",
                "selection": {"n_clusters": 2},
                # One fold, one algorithm: every kind of report, as few notebooks as possible.
                "folds": ["R2"],
                "paper_fold": "R2",
                "models": {"algorithms": ["mlr"]},
                "figures": {"algorithms": ["mlr"], "formats": ["png"], "dpi": 80},
                "reports": {"model_algorithms": ["mlr"]},
            }
        )
    )
    built = Built(work=work, out=work / "results" / "rep", dataset=dataset, config=config, env=snakemake_env())
    reports_snakemake(built)
    return built


# --------------------------------------------------------------------------- pytest-xdist

# Test files whose tests share one expensive session fixture. `make test` runs pytest-xdist
# workers with ``--dist loadgroup``: each group below goes to one worker, which builds the
# run once (session fixtures are per worker), and every other file is a unit of its own.
# (xdist 3.8's own loadgroup marks do not group under pytest 9, which no longer reads the
# node id xdist rewrites; the scheduler below groups by file instead.)
SHARED_RUN_FILES = {
    "tests/slurm/test_slurm_workflow.py": "slurm",
    "tests/workflow/test_workflow.py": "lines_run",
    "tests/workflow/test_compensation_workflow.py": "lines_run",
    "tests/workflow/test_interrupted_run.py": "lines_run",
    "tests/workflow/test_sweep_workflow.py": "lines_run",
    "tests/workflow/test_reports.py": "built",
    "tests/workflow/test_browser.py": "built",
}
_FIRST = ("slurm", "lines_run", "built")  # the longest chains start first


def _unit_of(nodeid: str) -> str:
    path = nodeid.split("::", 1)[0]
    return SHARED_RUN_FILES.get(path, path)


def pytest_collection_modifyitems(config, items):
    """The shared runs' files first; a test using a shared run outside its group is an error."""
    for item in items:
        for fixture in ("lines_run", "built"):
            if fixture in getattr(item, "fixturenames", ()) and _unit_of(item.nodeid) != fixture:
                raise pytest.UsageError(f"{item.nodeid} uses {fixture}: list its file in conftest.SHARED_RUN_FILES")
    rank = {group: i for i, group in enumerate(_FIRST)}
    items.sort(key=lambda item: rank.get(_unit_of(item.nodeid), len(rank)))


def pytest_xdist_make_scheduler(config, log):
    if config.getoption("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class SharedRunScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return _unit_of(nodeid)

    config.option.loadscopereorder = False  # keep the collection order: shared runs first
    return SharedRunScheduling(config, log)
