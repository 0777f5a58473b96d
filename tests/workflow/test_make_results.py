"""`make results` after a user ran one target of a dataset of their own (issue 24), and
what it prints (issue 34).

The cross-dataset summary, the recipe's last step, reads only the datasets of config
``datasets``: a half-built folder of another dataset beside them (no provenance yet) no
longer stops it. The checkout is a scratch copy: its own ``config/config.yaml`` lists one
tiny dataset, and ``make`` uses the test's interpreter (``VENV``, with ``-o env`` so the
environment is not rebuilt).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml

from helpers import REPO
from helpers.builders import write_dataset
from helpers.workflow import SNAKEMAKE, snakemake_env

pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="make is not installed")


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
        figures={**config.get("figures", {}), "algorithms": ["mlr"], "formats": ["png"]},
        reports={**config.get("reports", {}), "model_algorithms": []},
    )
    (root / "config" / "config.yaml").write_text(yaml.safe_dump(config), encoding="utf-8")
    for name in ("a", "mine"):
        write_dataset(root / "data" / name, name=name)
    return root


def _run(args, cwd: Path) -> subprocess.CompletedProcess:
    proc = subprocess.run(
        args, cwd=cwd, capture_output=True, text=True, env=snakemake_env(), timeout=1200
    )
    assert proc.returncode == 0, f"{args} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-5000:]}"
    return proc


def test_make_results_after_one_target_of_an_extra_dataset(tmp_path):
    checkout = _checkout(tmp_path / "checkout")
    _run(
        [SNAKEMAKE, "--cores", "2", "--config", "dataset=data/mine", "--",
         "results/mine/tables/metrics.csv"],
        checkout,
    )  # fmt: skip
    assert not (checkout / "results" / "mine" / "provenance.json").exists()
    venv = Path(sys.executable).parent.parent
    proc = _run(["make", "-o", "env", "results", f"VENV={venv}", "CORES=2"], checkout)
    # The quiet terminal (issue 34): a cold run of the dataset in at most 80 lines, each
    # warning text once, and the answer last, naming the page to open.
    lines = proc.stdout.splitlines() + proc.stderr.splitlines()
    assert len(lines) <= 80, "\n".join(lines)
    warnings = [line for line in lines if line.startswith("thermaxis warning:")]
    assert len(warnings) == len(set(warnings)), warnings
    last = proc.stdout.splitlines()[-1]
    assert last.startswith("a: ") and last.endswith("See results/a/index.html"), last
    assert last.split(": ", 1)[1].startswith(
        ("Deploy ", "Not yet: ", "Do not compensate with any candidate.")
    ), last
    summary = pd.read_csv(checkout / "results" / "_datasets" / "summary.csv")
    assert summary["dataset"].unique().tolist() == ["a"]
    assert (checkout / "results" / "a" / "provenance.json").is_file()
