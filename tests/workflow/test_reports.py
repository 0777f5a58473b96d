"""Reports end to end: every notebook executed by papermill, the index, provenance, reruns."""

from __future__ import annotations

import hashlib
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path
from urllib.parse import unquote, urlparse

import nbformat
import pytest
import yaml

from helpers import REPO
from helpers.runs import BUILT_RUNS
from helpers.runs import reports_snakemake as snakemake
from helpers.workflow import planned_rules, run_snakemake
from thermaxis.reports import provenance


def report_pages(out: Path) -> list[Path]:
    names = ["paper_report", "dataset_report", "condition_01", "condition_02", "model_02"]
    return [out / "reports" / f"{n}.html" for n in names]


def test_every_report_and_the_index_are_built(built):
    for page in report_pages(built.out):
        assert page.is_file(), page
        assert page.with_suffix(".ipynb").is_file(), page
    assert (built.out / "index.html").is_file()
    # One model report per fold, every approach side by side.
    assert sorted(p.name for p in (built.out / "reports").glob("model_*.html")) == ["model_02.html"]
    page = (built.out / "reports" / "model_02.html").read_text(encoding="utf-8")
    assert "<h3>decoupled MLR</h3>" in page and "<h3>pointwise MLR</h3>" in page
    # The paper report's Table 5 is the exact lines the dataset was written from
    # (helpers.builders.write_dataset's default: k = -10 + 0.5 m + r, b = -0.7 m - 0.1 r;
    # adding 0.0 prints -0.0 as the table does, 0.00).
    paper = (built.out / "reports" / "paper_report.html").read_text(encoding="utf-8")
    text = " ".join(re.sub(r"<[^>]+>", " ", paper).split())
    table = text[text.index("Table 5 reproduced") :]
    rows = " ".join(
        f"{run} {m + 1} {20.0 * m:.2f} {-10 + 0.5 * m + r:.2f} {-0.7 * m - 0.1 * r + 0.0:.2f} 1.00 0.00"
        for r, run in enumerate(BUILT_RUNS)
        for m in range(4)
    )
    assert rows in table, table[:600]


def test_first_screen_says_the_data_are_simulated(built):
    for page in report_pages(built.out):
        text = page.read_text(encoding="utf-8")
        body = text[text.index("<body") :]
        first_content = min(body.find(tag) for tag in ("<table", "<img", "<h2") if tag in body)
        banner = body.index('class="tx-banner')
        assert banner < first_content, page.name
        first_screen = body[banner:first_content]
        assert (
            "SIMULATED DATA" in first_screen
            and "Dataset <code>rep</code>: SIMULATED data" in first_screen
        ), page.name


def test_pages_load_nothing_from_the_network(built):
    remote = r"""\s*=\s*["']?\s*(?:https?:)?//"""
    patterns = {
        "remote src": re.compile(r"\bsrc" + remote, re.I),
        "remote stylesheet": re.compile(r"<link\b[^>]*\bhref" + remote, re.I),
        "remote CSS url()": re.compile(r"""url\(\s*["']?\s*(?:https?:)?//""", re.I),
        "CSS import": re.compile(r"@import", re.I),
        "image not embedded": re.compile(r"""<img\b[^>]*\bsrc\s*=\s*(?!["']?data:)""", re.I),
    }
    for page in [*report_pages(built.out), built.out / "index.html"]:
        text = page.read_text(encoding="utf-8")
        for what, pattern in patterns.items():
            # The index shows the figures' own PNGs as thumbnails: files of the dataset's folder.
            if what == "image not embedded" and page.name == "index.html":
                continue
            assert not pattern.search(text), (page.name, what, pattern.search(text).group(0))
        assert "<script src" not in text, page.name
    index = built.out / "index.html"
    thumbnails = re.findall(r'<img src="([^"]+)"', index.read_text(encoding="utf-8"))
    assert thumbnails and all(
        (index.parent / t).resolve().is_relative_to(built.out.resolve())
        and (index.parent / t).is_file()
        for t in thumbnails
    ), thumbnails


def test_executed_notebooks_keep_outputs_but_no_time_stamps(built):
    for page in report_pages(built.out):
        nb = nbformat.read(page.with_suffix(".ipynb"), as_version=4)
        assert "start_time" not in nb.metadata["papermill"]
        assert all("execution" not in c.metadata for c in nb.cells)
        assert any(c.get("outputs") for c in nb.cells if c.cell_type == "code")
        injected = [c for c in nb.cells if "injected-parameters" in c.metadata.get("tags", [])]
        assert [c.id for c in injected] == ["injected-parameters"]


def test_provenance_json_records_code_config_data_and_software(built):
    record = json.loads((built.out / "provenance.json").read_text(encoding="utf-8"))
    assert set(provenance.REQUIRED_KEYS) <= set(record)
    files = record["data"]["files"]
    on_disk = sorted(
        p.relative_to(built.dataset).as_posix() for p in built.dataset.rglob("*") if p.is_file()
    )
    assert sorted(files) == on_disk
    assert (
        files["runs.tsv"] == hashlib.sha256((built.dataset / "runs.tsv").read_bytes()).hexdigest()
    )
    assert (
        files["02/errors/M03.csv"]
        == hashlib.sha256((built.dataset / "02/errors/M03.csv").read_bytes()).hexdigest()
    )
    assert record["config"]["selection"]["n_clusters"] == 2
    canonical = json.dumps(record["config"], sort_keys=True, separators=(",", ":")).encode()
    assert record["config_sha256"] == hashlib.sha256(canonical).hexdigest()
    assert record["run_time"] == "2023-11-14T22:13:20Z"
    assert record["python"]["version"] == ".".join(map(str, sys.version_info[:3]))
    if not shutil.which("git"):
        pytest.skip("git is not installed: the commit in provenance.json is not checked")
    head = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True, check=True
    )
    assert record["git"]["commit"] == head.stdout.strip()


def test_index_links_every_report_figure_and_table(built):
    index = built.out / "index.html"
    hrefs = re.findall(r'<a href="([^"]+)"', index.read_text(encoding="utf-8"))
    # Anchors within the page; the page across datasets is made after every dataset's run
    # (thermaxis run, make results), so test_browser checks that link.
    hrefs = [h for h in hrefs if not h.startswith("#") and h != "../index.html"]
    targets = {(index.parent / unquote(urlparse(h).path)).resolve() for h in hrefs}
    assert all(t.is_file() for t in targets), [str(t) for t in targets if not t.is_file()]
    expected = {p.resolve() for p in report_pages(built.out)}
    expected |= {p.resolve() for p in (built.out / "figures").iterdir()}
    expected |= {
        (built.out / "tables" / n).resolve()
        for n in ("metrics.csv", "paper_comparison.md", "table5_slope_intercept.csv")
    }
    assert expected <= targets, sorted(str(p) for p in expected - targets)
    assert (built.out / "provenance.json").resolve() in targets


def test_nothing_reruns_and_a_rebuilt_report_is_byte_identical(built):
    """A dataset report and a model report made again, in new processes, have the same bytes
    (the session's `lines_run` makes no model reports, so this is where they are checked)."""
    assert planned_rules(snakemake(built, "-n")) - {"all"} == set()
    pages = [built.out / "reports" / name for name in ("dataset_report.html", "model_02.html")]
    before = [(page.read_bytes(), page.with_suffix(".ipynb").read_bytes()) for page in pages]
    rules = ("dataset_report", "model_report")
    snakemake(built, "--forcerun", *rules, "--until", *rules)
    assert [
        (page.read_bytes(), page.with_suffix(".ipynb").read_bytes()) for page in pages
    ] == before


def test_changing_n_clusters_reruns_only_the_affected_reports(built):
    changed = built.work / "n_clusters_3.yaml"
    doc = yaml.safe_load(built.config.read_text())
    doc["selection"]["n_clusters"] = 3
    changed.write_text(yaml.safe_dump(doc))
    proc = run_snakemake(
        built.work, "-n", "--configfile", str(changed), check=False, env=built.env, timeout=300
    )
    rules = planned_rules(proc) - {"all"}
    # The dataset report leads with the answer (recommendation and verdict), so it
    # follows the selection too; what the data are (cleaning, assembly) does not.
    assert {
        "models",
        "model_report",
        "paper_report",
        "dataset_report",
        "index",
    } <= rules, rules
    assert not rules & {
        "condition_report",
        "data_manifest",
        "clean",
        "assemble",
        "fig_data",
    }, rules
