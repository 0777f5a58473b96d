"""The bench's steps, each measured in a scratch work folder."""

from __future__ import annotations

import os
import platform
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml

from thermaxis.config import load_config
from thermaxis.dataset.safety import load_yaml
from thermaxis.pipeline import paths
from tools.bench import records as bench_records
from tools.bench.measure import MIB, Measurement, _add_jobs, measure
from tools.bench.report import finish
from tools.bench.scaling import GROWTH_SHAPES, SCALE_RUNS, SCALE_SHAPES, generate_command

REPO = Path(__file__).resolve().parents[2]
STEPS = (
    "startup",
    "dryrun",
    "results",
    "sweep",
    "subsets",
    "scale",
    "records",
    "devrecords",
    "twin_calibrate",
    "test",
)
SUBSET_SHAPE = {"sensors": 22, "positions": 1, "hours": 5.0, "rate_hz": 0.1, "measurement_min": 10.0, "seed": 0}  # fmt: skip
SUBSET_RUNS = 5
TWIN_RESUME = "src/thermaxis/twin_params.heldout_restarts.json"  # the Makefile's RESUME
SUBSET_SWEEP = {"methods": ["subset"], "n_clusters": [3], "approaches": ["pointwise"], "algorithms": ["mlr"],
                "max_subsets": 2000}  # fmt: skip
# Startup and dry-run timings are a few seconds each, so each is the best of this many.
DRYRUN_REPEATS = 3
# The smallest workflow Snakemake can run: its no-op is the floor a no-op rerun is measured against.
ONE_RULE_SNAKEFILE = (
    'rule all:\n    output:\n        "done.txt"\n    shell:\n        "touch {output}"\n'
)
# The same rule with one parameter: to hash a finished job's parameters, Snakemake imports
# pandas whenever it is installed (docs/performance.md, twelfth session).
ONE_RULE_PARAMS_SNAKEFILE = ONE_RULE_SNAKEFILE.replace(
    "    shell:", "    params:\n        x=1\n    shell:"
)


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
    ranking = work / "results" / dataset_name / paths.SWEEP_RANKING
    if not ranking.is_file():
        return {}
    import pandas as pd

    table = pd.read_csv(ranking)
    return {"configurations": int(len(table)), "folds": int(table["n_folds"].max())}


def run_bench(  # noqa: PLR0915 -- the steps in the order they run, each one a helper call
    out: Path,
    cores: int,
    runs=SCALE_RUNS,
    steps=STEPS,
    workdir: Path | None = None,
    keep: bool = False,
    timeout_s: float = 3600.0,
    progress=print,
    shapes=GROWTH_SHAPES,
    repeats: int = DRYRUN_REPEATS,
) -> dict:
    """Run the benchmark and return the bench.json document (also written to ``out``)."""
    out.mkdir(parents=True, exist_ok=True)
    scratch = Path(workdir) if workdir else Path(tempfile.mkdtemp(prefix="thermaxis-bench-"))
    scratch.mkdir(parents=True, exist_ok=True)
    env = _environment()
    logs = out / "logs"
    doc = _document(cores, runs, steps, shapes)
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
            for m in _dry_runs(scratch, cores, env, logs, timeout_s, repeats):
                record(m)
        if "results" in steps or "sweep" in steps:
            work = prepare_workdir(scratch / "default")
            dataset_name = _default_dataset_name(REPO)
        if "results" in steps:
            for m in _results_steps(work, scratch, cores, env, logs, timeout_s):
                record(m)
        if "sweep" in steps:
            m = record(measure("sweep_default", _snakemake(cores, "sweep"), work, logs / "sweep_default.log",
                               "snakemake sweep, default grid (assembled data present)", env, timeout_s))  # fmt: skip
            m.extra.update(_sweep_size(work, dataset_name))
        if "startup" in steps:
            for m in _startup(scratch, cores, env, logs, timeout_s, repeats):
                record(m)
        if "subsets" in steps:
            record(_subset_sweep(scratch, logs, cores, env, timeout_s, keep))
        if "scale" in steps:
            for shape in shapes:
                spec = SCALE_SHAPES[shape]
                for n in runs:
                    _scale_run(scratch, logs, shape, spec, n, cores, env, timeout_s, keep, record)
        if "records" in steps:
            for m, quality in _record_runs(scratch, cores, env, logs, timeout_s):
                record(m)
                if quality is not None:
                    doc.setdefault("records", []).append(quality)
        if "devrecords" in steps:
            for m, quality in _dev_record_runs(scratch, cores, env, logs, timeout_s):
                record(m)
                if quality is not None:
                    doc.setdefault("dev_records", []).append(quality)
        if "twin_calibrate" in steps:
            record(_twin_calibrate(scratch, env, logs, timeout_s))
        if "test" in steps:
            record(_test_suite(env, logs, timeout_s))
    finally:
        if not keep and workdir is None:
            shutil.rmtree(scratch, ignore_errors=True)
    doc["machine"]["load_average_at_end"] = [round(v, 2) for v in os.getloadavg()]
    return finish(doc, measurements, out)


def _document(cores: int, runs, steps, shapes) -> dict:
    """bench.json before any measurement: the machine, the commit and the settings."""
    doc = {
        "machine": _machine(),
        "git_commit": _git_commit(REPO),
        "settings": {
            "cores": cores,
            "scale_runs": list(runs),
            "scale_shapes": {shape: SCALE_SHAPES[shape] for shape in shapes},
            "steps": list(steps),
        },
        "measurements": [],
    }
    return doc


def _one_rule_workdir(folder: Path, snakefile: str = ONE_RULE_SNAKEFILE) -> Path:
    """``folder`` holding only ``snakefile``: a floor the workflow's start-up is measured against."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "Snakefile").write_text(snakefile)
    return folder


def _results_steps(work: Path, scratch: Path, cores: int, env: dict, logs: Path, timeout_s: float):
    """``make results`` cold, then with nothing to do, beside the one-rule floors, then after
    one model parameter changed; each measurement yielded as soon as it is made."""
    yield measure("results_cold", _snakemake(cores), work, logs / "results_cold.log",
                  "snakemake --cores N on nothing (make results after set-up)", env, timeout_s)  # fmt: skip
    yield measure("results_noop", _snakemake(cores), work, logs / "results_noop.log",
                  "the same again: nothing to do", env, timeout_s)  # fmt: skip
    for name, snakefile, what in (
        ("one_rule_noop", ONE_RULE_SNAKEFILE,
         "a one-rule Snakemake workflow with nothing to do (the floor)"),
        ("one_rule_params_noop", ONE_RULE_PARAMS_SNAKEFILE,
         "the same rule with one params entry (Snakemake then imports pandas)"),
    ):  # fmt: skip
        baseline = _one_rule_workdir(scratch / name, snakefile)
        subprocess.run(
            _snakemake(cores),
            cwd=baseline,
            env=env,
            capture_output=True,
            check=True,
            timeout=timeout_s,
        )
        yield measure(name, _snakemake(cores), baseline, logs / f"{name}.log", what, env, timeout_s)
    base = yaml.safe_load((REPO / "config" / "config.yaml").read_text(encoding="utf-8"))
    alpha = float(base.get("models", {}).get("ridge_alpha", 1.0)) * 2.0
    (work / "bench_param.yaml").write_text(yaml.safe_dump({"models": {"ridge_alpha": alpha}}))
    yield measure("results_model_param",
                  _snakemake(cores, "--configfile", "config/config.yaml", "bench_param.yaml"),
                  work, logs / "results_model_param.log",
                  f"after changing one model parameter (models.ridge_alpha -> {alpha:g})", env,
                  timeout_s)  # fmt: skip


def _record_runs(scratch: Path, cores: int, env: dict, logs: Path, timeout_s: float):
    """The workflow on each configured dataset and each channel of the imported records:
    (measurement, its quality row or None)."""
    work = prepare_workdir(scratch / "records")
    datasets = [REPO / d for d in load_config(REPO / "config" / "config.yaml")["datasets"]]
    datasets += bench_records.import_channels(REPO, scratch / "records_data", env, timeout_s)
    return bench_records.run_records(
        datasets, work, lambda *a: _snakemake(cores, *a), measure, logs, env, timeout_s
    )


def _dev_record_runs(scratch: Path, cores: int, env: dict, logs: Path, timeout_s: float):
    """The recommendation of each simulated development record (tools.bench.records.DEV_RECORDS)."""
    datasets = bench_records.dev_records(scratch / "dev_data", env, timeout_s)
    work = prepare_workdir(scratch / "dev_records")
    return bench_records.run_records(
        datasets, work, lambda *a: _snakemake(cores, *a), measure, logs, env, timeout_s
    )


def _twin_calibrate(scratch: Path, env: dict, logs: Path, timeout_s: float) -> Measurement:
    """``make twin-calibrate`` from the committed resume point, and whether it gives the
    committed parameters again."""
    # Into the scratch folder: the committed parameters and data stay as they are.
    target = scratch / "twin_calibrate"
    command = [sys.executable, "-m", "thermaxis.twin", "calibrate",
               "--out", str(target / "raw"), "--truth", str(target / "truth"),
               "--params", str(target / "twin_params.json"),
               "--resume", str(REPO / TWIN_RESUME)]  # fmt: skip
    target.mkdir(parents=True, exist_ok=True)
    m = measure("twin_calibrate", command, REPO, logs / "twin_calibrate.log",
                "make twin-calibrate: the polish from the held-out RMSE restarts' end, "
                "then the regeneration", env, timeout_s)  # fmt: skip
    written = target / "twin_params.json"
    m.extra["reproduces_committed"] = written.is_file() and (
        written.read_bytes() == (REPO / "src/thermaxis/twin_params.json").read_bytes()
    )
    return m


def _test_suite(env: dict, logs: Path, timeout_s: float) -> Measurement:
    """The test suite, as ``make test`` runs it."""
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
    return measure("test_suite", suite, REPO,
                   logs / "test_suite.log", "the test suite, as make test runs it (set-up done)", env,
                   timeout_s)  # fmt: skip


def _scale_run(scratch, logs, shape: str, spec: dict, n: int, cores, env, timeout_s, keep, record):
    """Generate one scale dataset (timed apart) and run the default configuration end to end."""
    name = f"{shape}_{n}"
    data = scratch / "scale" / f"data_{name}"
    shutil.rmtree(data, ignore_errors=True)
    record(measure(f"scale_generate_{name}", generate_command(data, n, spec), scratch, logs / f"scale_generate_{name}.log",
                   f"python -m thermaxis.twin scale: {n} runs, {shape} (not part of the fit)", env, timeout_s,
                   runs=n))  # fmt: skip
    work = prepare_workdir(scratch / "scale" / f"work_{name}")
    (work / "bench_scale.yaml").write_text(
        yaml.safe_dump({"dataset": str(data), "ambient_sensor": "T1"})
    )
    command = _snakemake(cores, "--configfile", "config/config.yaml", "bench_scale.yaml")
    record(measure(f"scale_{name}", command, work, logs / f"scale_{name}.log",
                   f"{n} runs, {shape}: end to end (cleaning to the index, every figure and report), "
                   "default configuration", env, timeout_s, runs=n))  # fmt: skip
    if not keep:
        shutil.rmtree(data, ignore_errors=True)
        shutil.rmtree(work, ignore_errors=True)


def _subset_sweep(scratch: Path, logs: Path, cores: int, env: dict, timeout_s: float, keep: bool):
    """The sweep's exhaustive subset search on a generated 5-run, 22-sensor, one-position dataset."""
    data = scratch / "subsets" / "data"
    shutil.rmtree(data, ignore_errors=True)
    spec = SUBSET_SHAPE
    subprocess.run(generate_command(data, SUBSET_RUNS, spec), env=env, check=True, capture_output=True,
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
    scratch: Path, cores: int, env: dict, logs: Path, timeout_s: float, repeats: int
) -> list[Measurement]:
    """``snakemake --version`` and a one-rule no-op, in .venv and (if made) in .venv-slurm; best of ``repeats``."""
    one_rule = _one_rule_workdir(scratch / "startup_one_rule")
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
            out.append(
                _best_of(repeats, name, command, one_rule, logs, description, venv_env, timeout_s)
            )
    return out


def _dry_runs(
    scratch: Path, cores: int, env: dict, logs: Path, timeout_s: float, repeats: int
) -> list[Measurement]:
    """``snakemake -n`` of the twin in an empty work folder and of a one-rule workflow, best of ``repeats``."""
    twin = prepare_workdir(scratch / "dryrun_twin")
    one_rule = _one_rule_workdir(scratch / "dryrun_one_rule")
    cases = [
        (
            "dryrun_twin",
            twin,
            ["--config", "dataset=data/raw/twin"],
            "snakemake -n of the twin, nothing built",
        ),
        ("dryrun_one_rule", one_rule, [], "snakemake -n of a one-rule workflow (the floor)"),
    ]
    return [
        _best_of(
            repeats, name, _snakemake(cores, "-n", *args), cwd, logs, description, env, timeout_s
        )
        for name, cwd, args, description in cases
    ]


def _best_of(repeats: int, name: str, command, cwd: Path, logs: Path, description: str, env: dict,
             timeout_s: float) -> Measurement:  # fmt: skip
    """``command`` measured ``repeats`` times (logs ``<name>_<i>.log``): the fastest run that
    succeeded, or a failed one if none did."""
    runs = [measure(name, command, cwd, logs / f"{name}_{i}.log", description, env, timeout_s)
            for i in range(repeats)]  # fmt: skip
    return min(runs, key=lambda m: (not m.ok, m.wall_s))
