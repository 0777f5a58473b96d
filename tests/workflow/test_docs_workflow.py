"""`make docs` on the session's workflow run: the guides' result blocks are made from the
results tree, and a block the tree does not give is found stale."""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import REPO

pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="make is not installed")


def _make_docs(results: Path, guide: Path, *extra: str) -> subprocess.CompletedProcess:
    venv = Path(sys.executable).parent.parent
    return subprocess.run(
        ["make", "-s", "-o", "env", "-f", str(REPO / "Makefile"), "docs", f"VENV={venv}",
         f"RESULTS={results}", f"DOCS={guide}", *extra],
        cwd=REPO, capture_output=True, text=True, timeout=300,
    )  # fmt: skip


def test_make_docs_writes_the_answer_and_the_held_out_error_from_results(lines_run, tmp_path):
    results = lines_run.work / "results"
    guide = tmp_path / "guide.md"
    stale = (
        "Intro.\n\n<!-- results:begin answers lines -->\nDeploy x: 1.30 µm.\n<!-- results:end -->\n\n"
        "<!-- results:begin held-out lines -->\n<!-- results:end -->\nEnd.\n"
    )
    guide.write_text(stale, encoding="utf-8")
    proc = _make_docs(results, guide)
    assert proc.returncode == 0, proc.stderr
    text = guide.read_text(encoding="utf-8")
    assert text.startswith("Intro.\n\n") and text.endswith("<!-- results:end -->\nEnd.\n")
    assert "1.30 µm" not in text
    # The answer: model.json's verdict in the pages' words, the deployed model's mean
    # held-out RMSE (this run deploys the paper's configuration by config), and beside it
    # the recommendation's, the mean of recommendation.csv, worked out here with the csv module.
    out = lines_run.out
    model = json.loads((out / "compensation" / "model.json").read_text())
    verdict = model["deployment"]["verdict"]
    assert verdict["outcome"] in ("recommended", "not_established", "not_recommended")
    from thermaxis.compensation.verdict import verdict_sentence

    assert verdict_sentence(verdict, unit="µm") in text
    curve = [r["rmse"] for r in model["held_out_accuracy"] if r["target"] == "error"]
    assert f": paper, held-out RMSE {sum(curve) / len(curve):.2f} µm against" in text
    with open(out / "tables" / "recommendation.csv", encoding="utf-8") as fh:
        rows = [r for r in csv.DictReader(line for line in fh if not line.startswith("#"))]
    paper = sum(float(r["paper_rmse_um"]) for r in rows) / len(rows)
    rmse = sum(float(r["rmse_um"]) for r in rows) / len(rows)
    assert f"against {paper:.2f} µm for the paper's configuration" in text
    assert f"the runs recommend the super learner at {rmse:.2f} µm" in text
    # The held-out error: each approach x algorithm's mean RMSE over the folds of metrics.csv.
    with open(out / "tables" / "metrics.csv", encoding="utf-8") as fh:
        metrics = [r for r in csv.DictReader(fh) if r["target"] == "error"]
    for approach, algorithm in {(r["approach"], r["algorithm"]) for r in metrics}:
        values = [
            float(r["rmse"])
            for r in metrics
            if (r["approach"], r["algorithm"]) == (approach, algorithm)
        ]
        assert (
            f"| {approach} | {algorithm} | {len(values)} | {sum(values) / len(values):.2f} |"
            in text
        )
    # Fresh now; the stale text is found stale.
    assert _make_docs(results, guide, "DOCBLOCKS_ARGS=--check").returncode == 0
    guide.write_text(stale, encoding="utf-8")
    proc = _make_docs(results, guide, "DOCBLOCKS_ARGS=--check")
    assert proc.returncode != 0 and f"stale: {guide}: results block answers lines" in proc.stderr
