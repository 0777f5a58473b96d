"""`make results`, `make report`, `make sweep` and `thermaxis run` as a user meets them, on one
scratch checkout (issues 24, 34 and 62).

The checkout holds the workflow's entry points (symlinks), its own ``config/config.yaml``
listing one tiny dataset ``a``, and a second tiny
dataset ``mine`` of which a user ran one target. ``make`` uses the test's interpreter
(``VENV``, with ``-o env`` so the environment is not rebuilt) and runs each target's
recipe as the Makefile spells it. One cold `make results` is shared by the tests here
(a module fixture: this file is one pytest-xdist unit); each later test adds to it, in
file order.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from helpers import GUIDES, REPO
from helpers.builders import write_dataset
from helpers.workflow import SNAKEMAKE, snakemake_env
from thermaxis.reports.docblocks import blocks_of, render

pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="make is not installed")

VENV = Path(sys.executable).parent.parent
N_SAMPLES = 400  # the benchmark record's


def _checkout(root: Path) -> Path:
    """The workflow's entry points (symlinks) and a config that builds dataset ``a`` only."""
    root.mkdir()
    for name in ("Snakefile", "workflow", "notebooks", "Makefile", "envs", "pyproject.toml"):
        (root / name).symlink_to(REPO / name)
    shutil.copytree(REPO / "config", root / "config")
    config = yaml.safe_load((REPO / "config" / "config.yaml").read_text(encoding="utf-8"))
    config.update(
        datasets=["data/a"],
        ambient_sensor="S1",
        selection={**config["selection"], "n_clusters": 2},
        models={**config["models"], "algorithms": ["mlr", "svr"]},
        figures={**config.get("figures", {}), "algorithms": ["mlr"], "formats": ["png"], "dpi": 60},
        # One conditions report of both runs instead of one per run: a notebook fewer.
        reports={**config.get("reports", {}), "model_algorithms": [], "combined_above_runs": 1},
    )
    (root / "config" / "config.yaml").write_text(yaml.safe_dump(config), encoding="utf-8")
    for name in ("a", "mine"):
        write_dataset(root / "data" / name, name=name)
    # The published-protocol benchmark `make results` runs by default, on the record that
    # travels with the repository (its spec reaches the record through data/import).
    for name in ("data/import", "data/sources", "data/benchmarks/fl_thermal.yaml"):
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).symlink_to(REPO / name)
    return root


def _benchmark(folder: Path) -> Path:
    """A published-protocol spec on a record whose error is exactly 2 T1 - 1.5 T3 + 4 µm.

    The record has FL_THERMAL's columns (its import mapping, source swapped), every 15 s,
    random-walk temperatures; the ridge over the temperatures at alpha 1e-6 finds the
    line, so its test MAE is zero to well under 1e-3 µm, below the 1 µm 'published'.
    """
    rng = np.random.default_rng(0)
    temperatures = {
        f"t{i}(°C)": 20 + np.cumsum(rng.normal(0, 0.05, N_SAMPLES)) for i in range(1, 17)
    }
    record = pd.DataFrame(
        {"時間(s)": np.arange(N_SAMPLES) * 15.0, "spindle(RPM)": 2500.0, **temperatures}
    )
    record["ch1(um)"] = 2.0 * record["t1(°C)"] - 1.5 * record["t3(°C)"] + 4.0
    folder.mkdir(parents=True, exist_ok=True)
    record.to_csv(folder / "record.csv", index=False)
    (folder / "LICENSE").write_text("made by the test\n")
    mapping = yaml.safe_load((REPO / "data/import/fl_thermal.yaml").read_text(encoding="utf-8"))
    mapping.update(source="record.csv", licence_file="LICENSE")
    (folder / "mapping.yaml").write_text(
        yaml.safe_dump(mapping, allow_unicode=True), encoding="utf-8"
    )
    spec = {
        "name": "exact",
        "mapping": "mapping.yaml",
        "citation": "made by the test",
        "channels": ["ch1(um)"],
        "protocol": {"train": [0.0, 0.6], "test": [0.6, 0.8]},
        "published": {"metric": "mae_um", "models": [{"name": "reference", "values": [1.0]}]},
        "candidates": {"inputs": ["temperatures"], "lag_sets_min": [[]], "rate_sets_min": [[]],
                       "ridge_alpha": [1e-6], "validation_splits": 3},
    }  # fmt: skip
    (folder / "exact.yaml").write_text(yaml.safe_dump(spec), encoding="utf-8")
    return folder / "exact.yaml"


def _run(args, cwd: Path) -> subprocess.CompletedProcess:
    proc = subprocess.run(
        args, cwd=cwd, capture_output=True, text=True, env=snakemake_env(), timeout=1200
    )
    assert proc.returncode == 0, f"{args} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-5000:]}"
    return proc


def _make(target: str, checkout: Path, *variables: str) -> subprocess.CompletedProcess:
    """``make TARGET`` with the test's interpreter; ``-o`` marks prerequisites as made."""
    return _run(["make", "-o", "env", "-o", "results", target, f"VENV={VENV}", "CORES=2",
                 *variables], checkout)  # fmt: skip


def _lines(proc: subprocess.CompletedProcess) -> list[str]:
    return proc.stdout.splitlines() + proc.stderr.splitlines()


def _answer_ends(proc: subprocess.CompletedProcess, name: str) -> str:
    """The last line printed: the dataset's answer, naming its page."""
    last = proc.stdout.splitlines()[-1]
    assert last.startswith(f"{name}: ") and last.endswith(f"See results/{name}/index.html"), last
    assert last.split(": ", 1)[1].startswith(
        ("Deploy ", "Not yet: ", "Do not compensate with any candidate.")
    ), last
    return last


@dataclass(frozen=True)
class Made:
    checkout: Path
    proc: subprocess.CompletedProcess  # make results'


@pytest.fixture(scope="module")
def made(tmp_path_factory) -> Made:
    """`make results` (with the exact benchmark and FL_THERMAL's) after one target of the
    extra dataset."""
    checkout = _checkout(tmp_path_factory.mktemp("make") / "checkout")
    spec = _benchmark(checkout / "data" / "benchmarks")
    _run(
        [SNAKEMAKE, "--cores", "2", "--config", "dataset=data/mine", "--",
         "results/mine/tables/dataset_summary.csv"],
        checkout,
    )  # fmt: skip
    assert not (checkout / "results" / "mine" / "provenance.json").exists()
    proc = _run(
        ["make", "-o", "env", "results", f"VENV={VENV}", "CORES=2",
         f"BENCHMARKS={spec.relative_to(checkout)} data/benchmarks/fl_thermal.yaml"],
        checkout,
    )  # fmt: skip
    return Made(checkout, proc)


def test_make_results_after_one_target_of_an_extra_dataset(made):
    # The quiet terminal (issue 34): a cold run of the dataset in at most 80 lines, each
    # warning text once, and the answer last, naming the page to open.
    lines = _lines(made.proc)
    assert len(lines) <= 80, "\n".join(lines)
    warnings = [line for line in lines if line.startswith("thermaxis warning:")]
    assert len(warnings) == len(set(warnings)), warnings
    assert not any("skipped" in line or "../shared" in line for line in lines), lines
    _answer_ends(made.proc, "a")
    # The half-built extra dataset (no provenance.json) is not on the page yet.
    summary = pd.read_csv(made.checkout / "results" / "_datasets" / "summary.csv")
    assert summary["dataset"].unique().tolist() == ["a"]
    assert (made.checkout / "results" / "a" / "provenance.json").is_file()


def test_make_results_runs_the_benchmark_on_its_record(made):
    table = pd.read_csv(made.checkout / "results" / "_benchmarks" / "exact" / "comparison.csv")
    (row,) = table.to_dict("records")
    # The error is an exact line of the temperatures: the ridge finds it.
    assert row["mae_um"] < 1e-3 and row["below_best_published"]
    # Fit on the first 60 %, score 60-80 %: floor(0.6 x 400) and floor(0.8 x 400) - 240.
    assert (row["n_train"], row["n_test"]) == (240, 80)


def _blocks_held_by(results: Path) -> list[tuple]:
    """Every block of the guides whose datasets or benchmarks ``results`` holds, checked
    against it: made again from it, it must be the committed text."""
    checked = []
    for guide in GUIDES:
        for kind, names, body in blocks_of(guide.read_text(encoding="utf-8")):
            if all((results / n).is_dir() or (results / "_benchmarks" / n).is_dir() for n in names):
                assert render(kind, names, results, str(guide)) == body, (
                    f"{guide}: results block {kind} {' '.join(names)} differs from {results} "
                    "(make results, then make docs)"
                )
                checked.append((kind, *names))
    return sorted(set(checked))


def test_the_guides_result_blocks_say_what_this_results_tree_says(made):
    """The README's and the guides' blocks (thermaxis.reports.docblocks) of every dataset or
    benchmark this tree holds are the committed text: FL_THERMAL's benchmark, which `make
    results` ran here on the record in data/sources. The blocks of the embedded datasets'
    default runs need a `make results` of their own: where the checkout has one (a
    developer's machine), they are checked against it too, so a change of method that
    leaves a stale number in a guide fails here until `make docs`."""
    assert _blocks_held_by(made.checkout / "results") == [
        ("benchmark", "fl_thermal"),
        ("benchmark-line", "fl_thermal"),
    ]
    _blocks_held_by(REPO / "results")


def test_make_report_writes_snakemakes_report(made):
    out = made.checkout / "results" / "a"
    proc = _make("report", made.checkout)
    with zipfile.ZipFile(out / "report.zip") as archive:
        html = archive.read("report/report.html").decode("utf-8")
    # Every fold's prediction figure (one family job draws them all), labelled with its
    # fold, which the job's wildcards do not hold (issue 62's `'Wildcards' object has no
    # attribute 'fold'`).
    figures = sorted(p.name for p in (out / "figures").glob("error_prediction_*.png"))
    assert len(figures) == 2 * 2  # folds R1, R2 x decoupled, point-by-point (MLR)
    for name in figures:
        key = f'"results/a/figures/{name}": {{"name": "{name}"'
        assert key in html, name
        labels = html.split(key, 1)[1].split("}", 1)[0]
        assert f'"fold": "{name.split("_")[2]}"' in labels, (name, labels)
    _answer_ends(proc, "a")


def test_make_sweep_plans_the_sweep_of_the_first_dataset(made):
    """A dry run: test_sweep_workflow runs the sweep target for real. The recipe is the
    Makefile's, its options' variable given Snakemake's dry-run flag after ``--``."""
    proc = _make("sweep", made.checkout, "THERMAXIS_OPTIONS=--cores 2 -- --dry-run")
    out = proc.stdout + proc.stderr
    assert "This was a dry-run" in out
    # The job table of the rich logger: the sweep's batches, its collection and report.
    for rule in ("sweep batch", "sweep collect", "sweep report"):
        assert re.search(rf"^\s*{rule}\s+\d+\s*$", out, flags=re.M), (rule, out[-2000:])
    assert not (made.checkout / "results" / "a" / "sweep").exists()


def test_thermaxis_run_of_one_more_dataset_prints_as_make_results_and_keeps_the_others(made):
    proc = _run([str(VENV / "bin" / "thermaxis"), "run", "data/mine", "--cores", "2"],
                made.checkout)  # fmt: skip
    lines = _lines(proc)
    assert len(lines) <= 80, "\n".join(lines)
    assert lines[0] == "== data/mine"
    assert not any(line.startswith("rule ") for line in lines), "Snakemake's full output"
    warnings = [line for line in lines if line.startswith("thermaxis warning:")]
    assert len(warnings) == len(set(warnings)), warnings
    _answer_ends(proc, "mine")
    # The page across datasets lists every dataset under results/, not only this one.
    results = made.checkout / "results"
    summary = pd.read_csv(results / "_datasets" / "summary.csv")
    assert sorted(summary["dataset"].unique()) == ["a", "mine"]
    page = (results / "index.html").read_text(encoding="utf-8")
    assert 'href="a/index.html"' in page and 'href="mine/index.html"' in page


def test_thermaxis_run_verbose_prints_snakemakes_own_output(made):
    proc = _run([str(VENV / "bin" / "thermaxis"), "run", "data/a", "--verbose", "--", "-n"],
                made.checkout)  # fmt: skip
    out = proc.stdout + proc.stderr
    # Snakemake's default logger, not the rich plugin's.
    assert "Building DAG of jobs..." in out and "Workflow start" not in out, out[-3000:]
    # A dry run builds nothing: no summary, no answer.
    assert proc.stdout.splitlines()[0] == "== data/a"
    assert "held-out error of" not in out and "See results/a/index.html" not in out


def test_thermaxis_report_builds_the_pages_and_ends_with_the_answer(made):
    index = made.checkout / "results" / "a" / "index.html"
    index.unlink()
    proc = _run([str(VENV / "bin" / "thermaxis"), "report", "data/a", "--cores", "2"],
                made.checkout)  # fmt: skip
    assert index.is_file()
    _answer_ends(proc, "a")


def test_make_clean_removes_what_the_targets_wrote(made):
    _run(["make", "clean"], made.checkout)
    for name in ("results", "logs", "benchmarks", ".snakemake"):
        assert not (made.checkout / name).exists(), name
    assert (made.checkout / "data" / "a" / "dataset.yaml").is_file()
    assert os.path.islink(made.checkout / "Snakefile")
