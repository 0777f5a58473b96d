"""Benchmarks of the workflow (``make bench``): wall time, CPU time and peak memory.

``python -m tools.bench --out results/bench`` measures, each in a scratch work
folder (symlinks to the repository's Snakefile, config, workflow, notebooks and data,
so the repository's own ``results/`` are never touched):

* ``results_cold``: ``snakemake --cores N`` from nothing (the set-up, i.e. the
  virtual environment, already exists), the same as ``make results``;
* ``results_noop``: the same command again, with nothing to do;
* ``results_model_param``: after changing one model parameter (``models.ridge_alpha``);
* ``sweep_default``: ``snakemake sweep`` with the default grid (the assembled data exist);
* ``scale_<shape>_<n>``: the default configuration (every algorithm, every run held out
  once) up to ``tables/metrics.csv`` on twin-generated datasets of n runs shaped like a
  measured record (``python -m thermaxis.twin scale``: 24 sensors logged every 10 s,
  about 30 measurements per run, one every 10 min), with ONE target position
  (``one_position``) and, separately, 14 (``positions_14``).  Generating a dataset is
  timed separately (``scale_generate_<shape>_<n>``) and is not part of the fit;
* ``test_suite``: ``python -m pytest`` in the repository, as ``make test`` runs it once
  the environment exists;
* ``subsets``: the sweep's exhaustive search of every 3 of 22 sensors (1,540 subsets) on a
  generated dataset of 5 runs with one target position, point by point with MLR, every run
  held out once;
* ``records_<name>``: the recommendation of every embedded dataset and of the public
  FL_THERMAL record's channels 1-5 (:mod:`tools.bench_records`), with its mean held-out
  RMSE beside the plain nested ridge baseline's and the paper's configuration's;
* ``startup``: ``snakemake --version`` and the one-rule no-op in ``.venv`` and, when
  ``make slurm-env`` has made it, in ``.venv-slurm`` (the Slurm executor plugin
  installed; on a machine with the Slurm client and no controller its import waits for
  one, docs/slurm-plugin-startup.md);
* ``dryrun_twin`` beside ``dryrun_one_rule``: ``snakemake -n`` of the twin in an empty
  work folder (every job planned, nothing run: what parsing the workflow and building its
  DAG cost, which every Snakemake start pays, each Slurm job included) and of a one-rule
  workflow (the floor: Snakemake's own start-up); the best of three each.

Each command runs in its own process group.  Wall time is measured around it; CPU time
(user + system) and the largest single process's peak RSS come from ``os.wait4``, which
reports the whole process tree once it has been reaped; the peak RSS of the tree (all
processes alive at the same time, summed) is sampled with psutil every 0.2 s when psutil
is installed.  Results: ``bench.json`` and ``bench.md`` in ``--out``.  The figures are
what this machine measured; the targets of the project are shown beside them, never
asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np
import yaml

from thermaxis.config import load_config
from thermaxis.dataset.safety import load_yaml
from tools import bench_records

__all__ = [
    "Measurement",
    "ScaleFit",
    "measure",
    "fit_scaling",
    "prepare_workdir",
    "run_bench",
    "finish",
    "render",
    "bench_markdown",
    "main",
]

REPO = Path(__file__).resolve().parents[1]
SCALE_RUNS = (5, 10, 20, 50)
# 5 h at 0.1 Hz with a measurement every 10 min from 5 min in: 30 measurements per run.
SCALE_SHAPES = {
    "one_position": {"sensors": 24, "positions": 1, "hours": 5.0, "rate_hz": 0.1, "measurement_min": 10.0, "seed": 0},
    "positions_14": {"sensors": 24, "positions": 14, "hours": 5.0, "rate_hz": 0.1, "measurement_min": 10.0, "seed": 0},
}  # fmt: skip
MIB = 1024.0 * 1024.0
# Linux reports ru_maxrss in KiB, macOS in bytes.
_MAXRSS_UNIT = 1.0 if sys.platform == "darwin" else 1024.0
STEPS = (
    "startup",
    "dryrun",
    "results",
    "sweep",
    "subsets",
    "scale",
    "records",
    "twin_calibrate",
    "test",
)
SUBSET_SHAPE = {"sensors": 22, "positions": 1, "hours": 5.0, "rate_hz": 0.1, "measurement_min": 10.0, "seed": 0}  # fmt: skip
SUBSET_RUNS = 5
TWIN_RESUME = "src/thermaxis/twin_params.table3_restarts.json"  # the Makefile's RESUME
SUBSET_SWEEP = {"methods": ["subset"], "n_clusters": [3], "approaches": ["pointwise"], "algorithms": ["mlr"],
                "max_subsets": 2000}  # fmt: skip
DRYRUN_REPEATS = 3
TARGETS = {
    "results_cold": "cold full regeneration of the twin <= 30 s",
    "results_noop": "no-op rerun <= 1.25 x a one-rule workflow's no-op",
    "sweep_default": "default sweep (all configurations x all folds) <= 15 s",
    "scale_one_position_50": "50 runs x 30 measurements x 24 sensors, one position, default config <= 5 min within 4 GiB",
    "test_suite": "make test after set-up <= 180 s",
    "dryrun_twin": "dry run of the twin <= the one-rule dry run + 2 s CPU",
    "startup_slurm": "one-rule no-op with the Slurm plugin installed <= 1.5 x without it",
    "sweep_subsets": "exhaustive 3-of-22 subsets, 5 runs, single position <= 30 s",
    "twin_calibrate": "make twin-calibrate (staged, through the pipeline) <= 10 min on 2 cores",
}
# The smallest workflow Snakemake can run: its no-op is the floor a no-op rerun is measured against.
ONE_RULE_SNAKEFILE = (
    'rule all:\n    output:\n        "done.txt"\n    shell:\n        "touch {output}"\n'
)


# --------------------------------------------------------------------------- measuring


@dataclass
class Measurement:
    """One timed command."""

    name: str
    description: str
    command: list[str]
    wall_s: float
    cpu_s: float
    peak_rss_mib: float
    peak_tree_rss_mib: float | None
    returncode: int
    log: str
    runs: int | None = None
    extra: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.returncode == 0


class _TreeSampler(threading.Thread):
    """Largest summed RSS of a process and its descendants, sampled."""

    def __init__(self, pid: int, every_s: float = 0.2):
        super().__init__(daemon=True)
        self.pid, self.every_s = pid, every_s
        self.peak_bytes = 0
        self.available = True
        self._stop_event = threading.Event()

    def run(self) -> None:
        try:
            import psutil
        except ImportError:
            self.available = False
            return
        try:
            root = psutil.Process(self.pid)
        except psutil.Error:
            return
        while not self._stop_event.is_set():
            total = 0
            try:
                for proc in [root, *root.children(recursive=True)]:
                    try:
                        total += proc.memory_info().rss
                    except psutil.Error:
                        pass
            except psutil.Error:
                break
            self.peak_bytes = max(self.peak_bytes, total)
            self._stop_event.wait(self.every_s)

    def stop(self) -> None:
        self._stop_event.set()
        self.join(timeout=5)


def measure(
    name: str,
    command: list[str],
    cwd: Path,
    log_path: Path,
    description: str = "",
    env: dict | None = None,
    timeout_s: float | None = None,
    runs: int | None = None,
) -> Measurement:
    """Run ``command`` in ``cwd`` and measure it; stdout and stderr go to ``log_path``.

    Parameters
    ----------
    name, description : str
        Identify the measurement in bench.json.
    command : list of str
    cwd : Path
    log_path : Path
        Created (with its folder); overwritten.
    env : dict, optional
        Environment of the command (default: this process's).
    timeout_s : float, optional
        The process group is terminated after this long; the measurement keeps the
        time until then and a non-zero return code.
    runs : int, optional
        Number of runs of the dataset (scale series).

    Returns
    -------
    Measurement
        Wall time, CPU time (user + system of the whole process tree), the largest
        single process's peak RSS and, with psutil, the sampled peak RSS of the tree.
    """
    log_path.parent.mkdir(parents=True, exist_ok=True)
    with open(log_path, "wb") as log:
        start = time.perf_counter()
        proc = subprocess.Popen(
            command, cwd=cwd, env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True
        )
        sampler = _TreeSampler(proc.pid)
        sampler.start()
        timer = None
        if timeout_s:
            timer = threading.Timer(timeout_s, _terminate_group, args=(proc.pid,))
            timer.start()
        # wait4, not Popen.wait: its rusage covers the child and every descendant it reaped.
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        if timer is not None:
            timer.cancel()
        sampler.stop()
    proc.returncode = os.waitstatus_to_exitcode(status)
    return Measurement(
        name=name,
        description=description,
        command=[str(c) for c in command],
        wall_s=round(wall, 3),
        cpu_s=round(usage.ru_utime + usage.ru_stime, 3),
        peak_rss_mib=round(usage.ru_maxrss * _MAXRSS_UNIT / MIB, 1),
        peak_tree_rss_mib=round(sampler.peak_bytes / MIB, 1) if sampler.available else None,
        returncode=proc.returncode,
        log=str(log_path),
        runs=runs,
    )


def _terminate_group(pid: int) -> None:
    try:
        os.killpg(pid, signal.SIGTERM)
    except ProcessLookupError:
        pass


# --------------------------------------------------------------------------- scaling


@dataclass(frozen=True)
class ScaleFit:
    """Least-squares line of cost against runs, and how far the cost bends away from it."""

    intercept_s: float
    slope_s_per_run: float
    r2: float
    marginal_s_per_run: list
    quadratic_share: float
    statement: str


def fit_scaling(runs, seconds, quantity: str = "wall time") -> ScaleFit:
    """Fit ``seconds = intercept + slope * runs`` and say how the cost grows.

    The verdict comes from a least-squares parabola through the same points: the share
    of its quadratic term in the cost at the largest size (0 for a straight line, 1 for
    pure ``runs**2``).  Below 0.2 in size the growth is called linear.  The marginal
    costs (seconds per added run between consecutive sizes) are reported as well; the
    first of them is noisy because small datasets leave cores idle.

    Raises
    ------
    ValueError
        With fewer than two distinct run counts.
    """
    order = np.argsort(np.asarray(runs, dtype=float), kind="stable")
    x = np.asarray(runs, dtype=float)[order]
    y = np.asarray(seconds, dtype=float)[order]
    if x.size != y.size or np.unique(x).size < 2:
        raise ValueError(f"scaling fit needs at least two distinct run counts, got runs={list(x)}")
    slope, intercept = np.polyfit(x, y, 1)
    residual = y - (intercept + slope * x)
    total = np.sum((y - y.mean()) ** 2)
    r2 = 1.0 - float(np.sum(residual**2) / total) if total > 0 else 1.0
    keep = np.diff(x) > 0
    marginal = [round(float(v), 3) for v in np.diff(y)[keep] / np.diff(x)[keep]]
    share = float("nan")
    if np.unique(x).size < 3:
        growth = "growth not judged: two sizes cannot show curvature"
    else:
        c2, c1, c0 = np.polyfit(x, y, 2)
        top = x[-1]
        share = float(c2 * top**2 / (c0 + c1 * top + c2 * top**2))
        if share < -0.2:
            growth = "cost grows less than linearly with the number of runs"
        elif share < 0.2:
            growth = "cost grows linearly with the number of runs"
        elif share < 0.5:
            growth = "cost grows somewhat faster than linearly with the number of runs"
        else:
            growth = "cost grows about quadratically (or faster) with the number of runs"
        growth += f" (quadratic share at {top:g} runs {share:.2f})"
    statement = (
        f"{quantity} = {intercept:.1f} s + {slope:.2f} s per run (least squares, R^2 = {r2:.3f}); {growth}; "
        f"marginal cost {', '.join(f'{v:.2f}' for v in marginal)} s per added run"
    )
    return ScaleFit(float(intercept), float(slope), r2, marginal, share, statement)


# --------------------------------------------------------------------------- the benchmark


def prepare_workdir(root: Path, repo: Path = REPO) -> Path:
    """A scratch work folder whose Snakefile, config, workflow, notebooks and data link to ``repo``."""
    root.mkdir(parents=True, exist_ok=True)
    for name in ("Snakefile", "config", "workflow", "notebooks", "data"):
        target = root / name
        if not target.exists():
            os.symlink(repo / name, target)
    return root


def _environment() -> dict:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env.setdefault("MPLBACKEND", "Agg")
    env.setdefault("PYTHONHASHSEED", "0")
    return env


def _snakemake(cores: int, *args: str) -> list[str]:
    return [str(Path(sys.executable).with_name("snakemake")), "--cores", str(cores), *args]


def _machine() -> dict:
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()
    memory = None
    try:
        import psutil

        memory = round(psutil.virtual_memory().total / MIB / 1024.0, 1)
    except ImportError:
        pass
    return {
        "cpu_count": os.cpu_count(),
        "usable_cores": usable,
        "memory_gib": memory,
        "platform": platform.platform(),
        "python": platform.python_version(),
        "load_average_at_start": [round(v, 2) for v in os.getloadavg()],
    }


def _git_commit(repo: Path) -> str | None:
    try:
        out = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=repo, capture_output=True, text=True, timeout=10
        )
        return out.stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        return None


def _default_dataset_name(repo: Path) -> str:
    """The dataset a plain ``snakemake`` run builds: the first of config ``datasets``."""
    meta = load_yaml(
        repo / load_config(repo / "config" / "config.yaml")["dataset"] / "dataset.yaml"
    )
    return meta["name"]


def _sweep_size(work: Path, dataset_name: str) -> dict:
    ranking = work / "results" / dataset_name / "sweep" / "ranking.csv"
    if not ranking.is_file():
        return {}
    import pandas as pd

    table = pd.read_csv(ranking)
    return {"configurations": int(len(table)), "folds": int(table["n_folds"].max())}


def run_bench(
    out: Path,
    cores: int,
    runs=SCALE_RUNS,
    steps=STEPS,
    workdir: Path | None = None,
    keep: bool = False,
    timeout_s: float = 3600.0,
    progress=print,
) -> dict:
    """Run the benchmark and return the bench.json document (also written to ``out``)."""
    out.mkdir(parents=True, exist_ok=True)
    scratch = Path(workdir) if workdir else Path(tempfile.mkdtemp(prefix="thermaxis-bench-"))
    env = _environment()
    logs = out / "logs"
    doc = {
        "machine": _machine(),
        "git_commit": _git_commit(REPO),
        "settings": {
            "cores": cores,
            "scale_runs": list(runs),
            "scale_shapes": SCALE_SHAPES,
            "steps": list(steps),
        },
        "measurements": [],
    }
    measurements: list[Measurement] = []

    def record(m: Measurement) -> Measurement:
        _add_jobs(m)
        measurements.append(m)
        status = "ok" if m.ok else f"FAILED (exit {m.returncode}, log {m.log})"
        progress(
            f"bench {m.name}: {m.wall_s:.1f} s wall, {m.cpu_s:.1f} s CPU, {m.peak_rss_mib:.0f} MiB peak; {status}"
        )
        return m

    try:
        if "dryrun" in steps:
            for m in _dry_runs(scratch, cores, env, logs, timeout_s):
                record(m)
        if "results" in steps or "sweep" in steps:
            work = prepare_workdir(scratch / "default")
            dataset_name = _default_dataset_name(REPO)
        if "results" in steps:
            record(measure("results_cold", _snakemake(cores), work, logs / "results_cold.log",
                                  "snakemake --cores N on nothing (make results after set-up)", env, timeout_s))  # fmt: skip
            record(measure("results_noop", _snakemake(cores), work, logs / "results_noop.log",
                           "the same again: nothing to do", env, timeout_s))  # fmt: skip
            baseline = scratch / "one_rule"
            baseline.mkdir(parents=True, exist_ok=True)
            (baseline / "Snakefile").write_text(ONE_RULE_SNAKEFILE)
            subprocess.run(
                _snakemake(cores),
                cwd=baseline,
                env=env,
                capture_output=True,
                check=True,
                timeout=timeout_s,
            )
            record(measure("one_rule_noop", _snakemake(cores), baseline, logs / "one_rule_noop.log",
                           "a one-rule Snakemake workflow with nothing to do (the floor)", env, timeout_s))  # fmt: skip
            base = yaml.safe_load((REPO / "config" / "config.yaml").read_text(encoding="utf-8"))
            alpha = float(base.get("models", {}).get("ridge_alpha", 1.0)) * 2.0
            (work / "bench_param.yaml").write_text(
                yaml.safe_dump({"models": {"ridge_alpha": alpha}})
            )
            record(measure("results_model_param",
                                     _snakemake(cores, "--configfile", "config/config.yaml", "bench_param.yaml"),
                                     work, logs / "results_model_param.log",
                                     f"after changing one model parameter (models.ridge_alpha -> {alpha:g})", env,
                                     timeout_s))  # fmt: skip
        if "sweep" in steps:
            m = record(measure("sweep_default", _snakemake(cores, "sweep"), work, logs / "sweep_default.log",
                               "snakemake sweep, default grid (assembled data present)", env, timeout_s))  # fmt: skip
            m.extra.update(_sweep_size(work, dataset_name))
        if "startup" in steps:
            for m in _startup(scratch, cores, env, logs, timeout_s):
                record(m)
        if "subsets" in steps:
            record(_subset_sweep(scratch, logs, cores, env, timeout_s, keep))
        if "scale" in steps:
            for shape, spec in SCALE_SHAPES.items():
                for n in runs:
                    _scale_run(scratch, logs, shape, spec, n, cores, env, timeout_s, keep, record)
        if "records" in steps:
            work = prepare_workdir(scratch / "records")
            datasets = [REPO / d for d in load_config(REPO / "config" / "config.yaml")["datasets"]]
            datasets += bench_records.import_channels(
                REPO, scratch / "records_data", env, timeout_s
            )
            for m, quality in bench_records.run_records(
                datasets, work, lambda *a: _snakemake(cores, *a), measure, logs, env, timeout_s
            ):
                record(m)
                if quality is not None:
                    doc.setdefault("records", []).append(quality)
        if "twin_calibrate" in steps:
            # Into the scratch folder: the committed parameters and data stay as they are.
            target = scratch / "twin_calibrate"
            command = [sys.executable, "-m", "thermaxis.twin", "calibrate",
                       "--out", str(target / "raw"), "--truth", str(target / "truth"),
                       "--params", str(target / "twin_params.json"),
                       "--resume", str(REPO / TWIN_RESUME)]  # fmt: skip
            target.mkdir(parents=True, exist_ok=True)
            m = measure("twin_calibrate", command, REPO, logs / "twin_calibrate.log",
                        "make twin-calibrate: the held-out RMSE restarts from the Table 3 restarts' end, "
                        "then the regeneration", env, timeout_s)  # fmt: skip
            written = target / "twin_params.json"
            m.extra["reproduces_committed"] = written.is_file() and (
                written.read_bytes() == (REPO / "src/thermaxis/twin_params.json").read_bytes()
            )
            record(m)
        if "test" in steps:
            workers = os.environ.get("PYTEST_WORKERS", "2")  # as the Makefile's test target
            suite = [
                sys.executable,
                "-m",
                "pytest",
                "-q",
                "-p",
                "no:cacheprovider",
                "-n",
                workers,
                "--dist",
                "loadgroup",
            ]
            record(measure("test_suite", suite, REPO,
                           logs / "test_suite.log", "the test suite, as make test runs it (set-up done)", env,
                           timeout_s))  # fmt: skip
    finally:
        if not keep and workdir is None:
            shutil.rmtree(scratch, ignore_errors=True)
    doc["machine"]["load_average_at_end"] = [round(v, 2) for v in os.getloadavg()]
    return finish(doc, measurements, out)


def _generate_command(out: Path, runs: int, spec: dict) -> list[str]:
    """``python -m thermaxis.twin scale`` writing ``runs`` runs of shape ``spec`` to ``out``."""
    options = ("sensors", "positions", "hours", "rate_hz", "measurement_min", "seed")
    flags = [[f"--{name.replace('_', '-')}", str(spec[name])] for name in options]
    return [sys.executable, "-m", "thermaxis.twin", "scale", "--out", str(out), "--runs", str(runs),
            *(part for flag in flags for part in flag)]  # fmt: skip


def _scale_run(scratch, logs, shape: str, spec: dict, n: int, cores, env, timeout_s, keep, record):
    """Generate one scale dataset (timed apart) and run the default configuration to metrics.csv."""
    name = f"{shape}_{n}"
    data = scratch / "scale" / f"data_{name}"
    shutil.rmtree(data, ignore_errors=True)
    record(measure(f"scale_generate_{name}", _generate_command(data, n, spec), scratch, logs / f"scale_generate_{name}.log",
                   f"python -m thermaxis.twin scale: {n} runs, {shape} (not part of the fit)", env, timeout_s,
                   runs=n))  # fmt: skip
    work = prepare_workdir(scratch / "scale" / f"work_{name}")
    (work / "bench_scale.yaml").write_text(
        yaml.safe_dump({"dataset": str(data), "ambient_sensor": "T1"})
    )
    command = _snakemake(cores, "--configfile", "config/config.yaml", "bench_scale.yaml", "--",
                         "results/twin_scale/tables/metrics.csv")  # fmt: skip
    record(measure(f"scale_{name}", command, work, logs / f"scale_{name}.log",
                   f"{n} runs, {shape}: cleaning to metrics.csv, default configuration (every algorithm, "
                   "every run held out)", env, timeout_s, runs=n))  # fmt: skip
    if not keep:
        shutil.rmtree(data, ignore_errors=True)
        shutil.rmtree(work, ignore_errors=True)


def _subset_sweep(scratch: Path, logs: Path, cores: int, env: dict, timeout_s: float, keep: bool):
    """The sweep's exhaustive subset search on a generated 5-run, 22-sensor, one-position dataset."""
    data = scratch / "subsets" / "data"
    shutil.rmtree(data, ignore_errors=True)
    spec = SUBSET_SHAPE
    subprocess.run(_generate_command(data, SUBSET_RUNS, spec), env=env, check=True, capture_output=True,
                   timeout=timeout_s)  # fmt: skip
    work = prepare_workdir(scratch / "subsets" / "work")
    override = {"dataset": str(data), "ambient_sensor": "T1", "sweep": SUBSET_SWEEP}
    (work / "bench_subsets.yaml").write_text(yaml.safe_dump(override))
    prefix = ["--configfile", "config/config.yaml", "bench_subsets.yaml", "--"]
    # The assembled tables first, untimed: the measurement is the sweep's.
    subprocess.run(_snakemake(cores, *prefix, "results/twin_scale/assembled/errors.parquet"), cwd=work, env=env,
                   check=True, capture_output=True, timeout=timeout_s)  # fmt: skip
    m = measure("sweep_subsets", _snakemake(cores, *prefix, "results/twin_scale/sweep/summary.csv"), work,
                logs / "sweep_subsets.log", "sweep of every 3 of 22 sensors (1,540 subsets), 5 runs, one position, "
                "point by point, MLR (assembled data present)", env, timeout_s, runs=SUBSET_RUNS)  # fmt: skip
    if not keep:
        shutil.rmtree(scratch / "subsets", ignore_errors=True)
    return m


def _startup(
    scratch: Path, cores: int, env: dict, logs: Path, timeout_s: float
) -> list[Measurement]:
    """``snakemake --version`` and a one-rule no-op, in .venv and (if made) in .venv-slurm; best of three."""
    one_rule = scratch / "startup_one_rule"
    one_rule.mkdir(parents=True, exist_ok=True)
    (one_rule / "Snakefile").write_text(ONE_RULE_SNAKEFILE)
    venvs = {"venv": Path(sys.executable).parent, "slurm": REPO / ".venv-slurm" / "bin"}
    out = []
    for label, bin_dir in venvs.items():
        snakemake = bin_dir / "snakemake"
        if not snakemake.is_file():
            continue
        venv_env = {**env, "PATH": f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"}
        subprocess.run([str(snakemake), "--cores", "1"], cwd=one_rule, env=venv_env,
                       capture_output=True, timeout=timeout_s)  # fmt: skip
        cases = [
            (f"startup_version_{label}", [str(snakemake), "--version"], f"snakemake --version ({bin_dir.parent.name})"),
            (f"startup_noop_{label}", [str(snakemake), "--cores", str(cores)],
             f"one-rule no-op ({bin_dir.parent.name})"),
        ]  # fmt: skip
        for name, command, description in cases:
            runs = [measure(name, command, one_rule, logs / f"{name}_{i}.log", description, venv_env, timeout_s)
                    for i in range(DRYRUN_REPEATS)]  # fmt: skip
            out.append(min(runs, key=lambda m: (not m.ok, m.wall_s)))
    return out


def _dry_runs(
    scratch: Path, cores: int, env: dict, logs: Path, timeout_s: float
) -> list[Measurement]:
    """``snakemake -n`` of the twin in an empty work folder and of a one-rule workflow, best of DRYRUN_REPEATS."""
    twin = prepare_workdir(scratch / "dryrun_twin")
    one_rule = scratch / "dryrun_one_rule"
    one_rule.mkdir(parents=True, exist_ok=True)
    (one_rule / "Snakefile").write_text(ONE_RULE_SNAKEFILE)
    cases = [
        (
            "dryrun_twin",
            twin,
            ["--config", "dataset=data/raw/twin"],
            "snakemake -n of the twin, nothing built",
        ),
        ("dryrun_one_rule", one_rule, [], "snakemake -n of a one-rule workflow (the floor)"),
    ]
    best = []
    for name, cwd, args, description in cases:
        runs = [
            measure(
                name,
                _snakemake(cores, "-n", *args),
                cwd,
                logs / f"{name}_{i}.log",
                description,
                env,
                timeout_s,
            )
            for i in range(DRYRUN_REPEATS)
        ]
        best.append(min(runs, key=lambda m: (not m.ok, m.wall_s)))
    return best


def finish(doc: dict, measurements: list[Measurement], out: Path) -> dict:
    """Add the measurements, the scaling fits and the targets to ``doc``; write bench.json and bench.md."""
    doc["measurements"] = [{**asdict(m), "ok": m.ok} for m in measurements]
    doc.pop("scale_fit", None)
    for shape in SCALE_SHAPES:
        scale = [m for m in measurements if m.name.startswith(f"scale_{shape}_") and m.ok]
        if len({m.runs for m in scale}) >= 2:
            doc.setdefault("scale_fit", {})[shape] = {
                "wall": asdict(fit_scaling([m.runs for m in scale], [m.wall_s for m in scale])),
                "cpu": asdict(
                    fit_scaling([m.runs for m in scale], [m.cpu_s for m in scale], "CPU time")
                ),
            }
    doc["targets"] = _targets(measurements) + [
        {
            "target": f"{q['record']}: recommendation <= {bench_records.RECORD_TARGETS['baseline']} x the nested "
            f"ridge baseline and <= {bench_records.RECORD_TARGETS['paper']} x the paper's configuration",
            "measured": f"{q['recommended_rmse_um']:.2f} um: {q['vs_baseline']:.2f} x {q['baseline_rmse_um']:.2f}, "
            f"{q['vs_paper']:.2f} x {q['paper_rmse_um']:.2f}",
            "met": q["met"],
        }
        for q in doc.get("records", [])
    ]
    out.mkdir(parents=True, exist_ok=True)
    (out / "bench.json").write_text(
        json.dumps(doc, indent=1, sort_keys=True) + "\n", encoding="utf-8"
    )
    (out / "bench.md").write_text(bench_markdown(doc), encoding="utf-8")
    return doc


def render(out: Path) -> dict:
    """Re-derive the fits, targets and bench.md from an existing ``out/bench.json`` (nothing is rerun)."""
    path = out / "bench.json"
    if not path.is_file():
        raise ValueError(f"{path}: not found; run the benchmark first")
    doc = json.loads(path.read_text(encoding="utf-8"))
    names = {f.name for f in fields(Measurement)}
    measurements = [
        Measurement(**{k: v for k, v in d.items() if k in names}) for d in doc["measurements"]
    ]
    for m in measurements:
        _add_jobs(m)
    return finish(doc, measurements, out)


def _add_jobs(m: Measurement) -> None:
    if Path(m.command[0]).name == "snakemake" and "jobs" not in m.extra:
        m.extra["jobs"] = _count_jobs(Path(m.log))


def _count_jobs(log: Path) -> int | None:
    """Jobs Snakemake ran, from its 'N of M steps' lines."""
    if not log.is_file():
        return None
    lines = log.read_text(errors="replace").splitlines()
    done = [line for line in lines if "steps (" in line and " of " in line]
    if not done:
        # A dry run plans jobs and runs none: its job stats end with "total <n>".
        planned = [
            line.split()[1]
            for line in lines
            if line.startswith("total ") and line.split()[1:2] != []
        ]
        return int(planned[-1]) if planned and planned[-1].isdigit() else 0
    try:
        return int(done[-1].split(" of ")[1].split()[0])
    except (IndexError, ValueError):
        return None


def _targets(measurements: list[Measurement]) -> list[dict]:
    by_name = {m.name: m for m in measurements}
    rows = []

    def add(name, met, measured):
        rows.append({"target": TARGETS[name], "measured": measured, "met": met})

    def add_ratio(name, m, floor, limit):
        ratio = m.wall_s / floor.wall_s
        add(
            name,
            m.ok and ratio <= limit,
            f"{m.wall_s:.1f} s vs {floor.wall_s:.1f} s: {ratio:.2f} x",
        )

    if "results_cold" in by_name:
        m = by_name["results_cold"]
        add("results_cold", m.ok and m.wall_s <= 30.0, f"{m.wall_s:.1f} s")
    if "results_noop" in by_name and "one_rule_noop" in by_name:
        add_ratio("results_noop", by_name["results_noop"], by_name["one_rule_noop"], 1.25)
    if "sweep_default" in by_name:
        m = by_name["sweep_default"]
        n = m.extra.get("configurations", 0)
        add("sweep_default", m.ok and m.wall_s <= 15.0,
            f"{n} configurations x {m.extra.get('folds', '?')} folds in {m.wall_s:.1f} s")  # fmt: skip
    if "dryrun_twin" in by_name and "dryrun_one_rule" in by_name:
        m, floor = by_name["dryrun_twin"], by_name["dryrun_one_rule"]
        extra = m.cpu_s - floor.cpu_s
        add("dryrun_twin", m.ok and extra <= 2.0,
            f"{m.wall_s:.1f} s wall, {m.cpu_s:.1f} s CPU vs {floor.wall_s:.1f} s, {floor.cpu_s:.1f} s: "
            f"+{m.wall_s - floor.wall_s:.1f} s wall, +{extra:.1f} s CPU")  # fmt: skip
    if "test_suite" in by_name:
        m = by_name["test_suite"]
        add("test_suite", m.ok and m.wall_s <= 180.0, f"{m.wall_s:.1f} s")
    if "scale_one_position_50" in by_name:
        m = by_name["scale_one_position_50"]
        peak = m.peak_tree_rss_mib if m.peak_tree_rss_mib is not None else m.peak_rss_mib
        add(
            "scale_one_position_50",
            m.ok and m.wall_s <= 300.0 and peak <= 4096.0,
            f"{m.wall_s:.1f} s, peak {peak:.0f} MiB",
        )
    if "sweep_subsets" in by_name:
        m = by_name["sweep_subsets"]
        add("sweep_subsets", m.ok and m.wall_s <= 30.0, f"{m.wall_s:.1f} s")
    if "twin_calibrate" in by_name:
        m = by_name["twin_calibrate"]
        add(
            "twin_calibrate",
            m.ok and m.wall_s <= 600.0,
            f"{m.wall_s:.1f} s on {os.cpu_count()} cores; "
            f"committed parameters reproduced: {m.extra.get('reproduces_committed')}",
        )
    if "startup_noop_slurm" in by_name and "startup_noop_venv" in by_name:
        add_ratio("startup_slurm", by_name["startup_noop_slurm"], by_name["startup_noop_venv"], 1.5)
    return rows


def bench_markdown(doc: dict) -> str:
    """bench.md: the machine, one row per measurement, the scaling statement, the targets."""
    machine = doc["machine"]
    lines = [
        "# thermaxis benchmark",
        "",
        f"Machine: {machine['usable_cores']} usable cores ({machine['cpu_count']} CPUs), "
        f"{machine.get('memory_gib')} GiB memory, {machine['platform']}, Python {machine['python']}. "
        f"Snakemake ran with `--cores {doc['settings']['cores']}`. Load average at start "
        f"{machine['load_average_at_start']}, at end {machine.get('load_average_at_end')} "
        "(other work on the machine inflates wall times).",
        "",
        "| measurement | wall (s) | CPU (s) | peak RSS, largest process (MiB) | peak RSS, process tree (MiB) | jobs | ok | what |",
        "|---|---:|---:|---:|---:|---:|---|---|",
    ]
    for m in doc["measurements"]:
        tree = "" if m["peak_tree_rss_mib"] is None else f"{m['peak_tree_rss_mib']:.0f}"
        jobs = m["extra"].get("jobs")
        what = m["description"]
        if "configurations" in m["extra"]:
            what += f"; {m['extra']['configurations']} configurations x {m['extra']['folds']} folds"
        lines.append(
            f"| {m['name']} | {m['wall_s']:.1f} | {m['cpu_s']:.1f} | {m['peak_rss_mib']:.0f} | {tree} | "
            f"{'' if jobs is None else jobs} | {'yes' if m['ok'] else 'NO'} | {what} |"
        )
    for shape, fit in doc.get("scale_fit", {}).items():
        lines += ["", f"Scaling of the scale series {shape}: {fit['wall']['statement']}.",
                  f"{fit['cpu']['statement']}."]  # fmt: skip
    if doc.get("records"):
        lines += [
            "",
            "Mean held-out RMSE (µm, leave-one-condition-out) of the recommendation, the plain nested ridge "
            "baseline (`baseline-ridge+lags`) and the paper's configuration (tools/bench_records.py):",
            "",
            "| record | folds | recommendation | nested ridge | paper's configuration | vs ridge | vs paper |",
            "|---|---:|---:|---:|---:|---:|---:|",
        ]
        lines += [
            f"| {q['record']} | {q['folds']} | {q['recommended_rmse_um']:.2f} | {q['baseline_rmse_um']:.2f} | "
            f"{q['paper_rmse_um']:.2f} | {q['vs_baseline']:.2f} | {q['vs_paper']:.2f} |"
            for q in doc["records"]
        ]
    if doc.get("targets"):
        lines += ["", "| target | measured | met |", "|---|---|---|"]
        lines += [
            f"| {t['target']} | {t['measured']} | {'yes' if t['met'] else 'no'} |"
            for t in doc["targets"]
        ]
    lines += [
        "",
        "Scale runs: SIMULATED twin-generated datasets shaped like a measured record (24 sensors logged "
        "every 10 s, 30 measurements per run, one position or 14), the default configuration from "
        "cleaning to `tables/metrics.csv` (every algorithm, every run held out once); figures and "
        "reports are not included. Peak RSS of the process tree is sampled every 0.2 s (psutil).",
    ]
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- command line


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tools.bench", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "--out", type=Path, default=Path("results/bench"), help="folder of bench.json and bench.md"
    )
    parser.add_argument(
        "--cores", type=int, default=None, help="cores given to Snakemake (default: all usable)"
    )
    parser.add_argument(
        "--runs", type=int, nargs="+", default=list(SCALE_RUNS), help="runs of the scale datasets"
    )
    parser.add_argument(
        "--steps", nargs="+", choices=STEPS, default=list(STEPS), help="what to measure"
    )
    parser.add_argument(
        "--workdir", type=Path, default=None, help="scratch folder (default: a new temporary one)"
    )
    parser.add_argument(
        "--keep", action="store_true", help="keep the scratch work folders and scale datasets"
    )
    parser.add_argument(
        "--timeout-s", type=float, default=3600.0, help="stop any one measurement after this long"
    )
    parser.add_argument(
        "--render-only",
        action="store_true",
        help="rewrite bench.md from --out/bench.json, rerun nothing",
    )
    args = parser.parse_args(argv)
    if args.render_only:
        try:
            render(args.out)
        except ValueError as exc:
            print(f"thermaxis error: {exc}", file=sys.stderr)
            return 2
        print((args.out / "bench.md").read_text(encoding="utf-8"))
        return 0
    cores = args.cores or _machine()["usable_cores"] or 1
    if cores < 1 or any(n < 1 for n in args.runs):
        print("thermaxis error: --cores and --runs must be positive integers", file=sys.stderr)
        return 2
    doc = run_bench(args.out, cores, args.runs, args.steps, args.workdir, args.keep, args.timeout_s,
                    progress=lambda line: print(line, file=sys.stderr, flush=True))  # fmt: skip
    print((args.out / "bench.md").read_text(encoding="utf-8"))
    return 0 if all(m["ok"] for m in doc["measurements"]) else 1


if __name__ == "__main__":
    sys.exit(main())
