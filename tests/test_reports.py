"""Reports: clean notebooks, provenance, HTML helpers, and the report rules end to end."""

from __future__ import annotations

import base64
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from urllib.parse import unquote, urlparse

import thermaxis  # noqa: F401  first: nbformat's jsonschema import is seconds faster (thermaxis/__init__.py)
import nbformat
import pandas as pd
import pytest
import yaml

from conftest import FIXED_EPOCH, REPO, run_snakemake, snakemake_env, workflow_workdir, write_dataset
from thermaxis import provenance, reporting

NOTEBOOKS = ("dataset_report", "condition_report", "model_report", "paper_report")


# --------------------------------------------------------------------------- notebooks


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_notebook_is_committed_without_outputs_and_has_a_parameters_cell(name):
    nb = nbformat.read(REPO / "notebooks" / f"{name}.ipynb", as_version=4)
    nbformat.validate(nb)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert all(c.outputs == [] and c.execution_count is None for c in code), f"{name}: clear the outputs before committing"
    tagged = [c for c in code if "parameters" in c.metadata.get("tags", [])]
    assert len(tagged) == 1 and tagged[0] is code[0], f"{name}: the first code cell must be the only one tagged 'parameters'"
    assert nb.metadata["kernelspec"]["name"] == "python3"
    assert "papermill" not in nb.metadata


# --------------------------------------------------------------------------- provenance


def test_sha256_of_a_known_file(tmp_path):
    path = tmp_path / "abc.txt"
    path.write_bytes(b"abc")
    # FIPS 180-2 test vector for "abc".
    assert provenance.sha256_file(path) == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"


def test_manifest_hashes_every_file_and_matches_sha256sum(tmp_path):
    (tmp_path / "R1" / "errors").mkdir(parents=True)
    (tmp_path / "runs.tsv").write_bytes(b"run\n")
    (tmp_path / "R1" / "errors" / "M01.csv").write_bytes(b"abc")
    (tmp_path / "R1" / "notes.txt").write_bytes(b"")
    manifest = provenance.data_manifest(tmp_path)
    assert list(manifest) == ["R1/errors/M01.csv", "R1/notes.txt", "runs.tsv"]
    assert manifest["R1/errors/M01.csv"] == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    # SHA-256 of the empty string (FIPS 180-2).
    assert manifest["R1/notes.txt"] == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
    if shutil.which("sha256sum"):
        listing = subprocess.run(["sha256sum", *manifest], cwd=tmp_path, capture_output=True, check=True).stdout
        assert provenance.manifest_sha256(manifest) == hashlib.sha256(listing).hexdigest()


def test_manifest_of_a_missing_folder_is_a_value_error(tmp_path):
    with pytest.raises(ValueError, match="dataset folder not found"):
        provenance.data_manifest(tmp_path / "nowhere")


def test_config_hash_ignores_key_order():
    a = {"selection": {"n_clusters": 3, "rho": 0.5}, "dataset": "d"}
    b = {"dataset": "d", "selection": {"rho": 0.5, "n_clusters": 3}}
    expected = hashlib.sha256(b'{"dataset":"d","selection":{"n_clusters":3,"rho":0.5}}').hexdigest()
    assert provenance.config_sha256(a) == provenance.config_sha256(b) == expected
    assert provenance.config_sections_sha256(a)["dataset"] == hashlib.sha256(b'"d"').hexdigest()
    assert provenance.config_sha256({**a, "dataset": "e"}) != expected


def test_run_time_honours_source_date_epoch(monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "0")
    assert provenance.run_time() == "1970-01-01T00:00:00Z"
    monkeypatch.setenv("SOURCE_DATE_EPOCH", FIXED_EPOCH)
    assert provenance.run_time() == "2023-11-14T22:13:20Z"
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "yesterday")
    with pytest.raises(ValueError, match="SOURCE_DATE_EPOCH"):
        provenance.run_time()
    assert provenance.run_time(datetime(2024, 2, 29, 12, 0, 5, tzinfo=timezone.utc)) == "2024-02-29T12:00:05Z"


@pytest.mark.skipif(shutil.which("git") is None, reason="git is not installed")
def test_git_state_commit_and_dirty_flag(tmp_path):
    repo = tmp_path / "repo"
    repo.mkdir()
    env = {**os.environ, "GIT_AUTHOR_NAME": "t", "GIT_AUTHOR_EMAIL": "t@t", "GIT_COMMITTER_NAME": "t", "GIT_COMMITTER_EMAIL": "t@t"}

    def git(*args):
        return subprocess.run(["git", "-C", str(repo), *args], capture_output=True, text=True, check=True, env=env).stdout

    git("init", "-q")
    (repo / "a.txt").write_text("1\n")
    git("add", "a.txt")
    git("commit", "-q", "-m", "first")
    head = git("rev-parse", "HEAD").strip()
    assert provenance.git_state(repo) == {"commit": head, "dirty": False}
    (repo / "untracked.txt").write_text("cache\n")
    assert provenance.git_state(repo)["dirty"] is False
    (repo / "a.txt").write_text("2\n")
    assert provenance.git_state(repo) == {"commit": head, "dirty": True}
    assert provenance.git_state(tmp_path / "elsewhere") == {"commit": None, "dirty": None}


def test_collect_has_every_required_key(tmp_path):
    (tmp_path / "runs.tsv").write_bytes(b"abc")
    record = provenance.collect(tmp_path, {"b": 1, "a": {"x": 2}}, tmp_path, git={"commit": "c0ffee", "dirty": False})
    assert set(provenance.REQUIRED_KEYS) <= set(record)
    assert record["git"] == {"commit": "c0ffee", "dirty": False}
    assert record["data"]["n_files"] == 1
    assert record["config"] == {"a": {"x": 2}, "b": 1}
    assert json.loads(provenance.to_json(record)) == record


# --------------------------------------------------------------------------- HTML helpers


def test_remote_loads_finds_scripts_styles_images_but_not_links():
    page = (
        '<script src="https://cdn.example.org/require.js"></script>'
        "<link rel='stylesheet' href='//fonts.example.org/a.css'>"
        '<img src="http://example.org/x.png">'
        "<style>@import url(https://example.org/b.css); .x{background:url('http://e.org/i.png')}</style>"
        '<a href="https://doi.org/10.19650/j.cnki.cjsi.J2209628">paper</a>'
        '<img src="data:image/png;base64,AAAA"><link rel="icon" href="data:,"><a href="../index.html">i</a>'
    )
    found = reporting.remote_loads(page)
    assert len(found) == 5
    assert not any("doi.org" in f for f in found)


def test_strip_volatile_drops_time_stamps_and_fixes_the_injected_cell_id():
    nb = {
        "metadata": {"papermill": {"start_time": "t0", "end_time": "t1", "duration": 1.5, "parameters": {"a": 1}}},
        "cells": [
            {"id": "random-uuid", "metadata": {"tags": ["injected-parameters"], "papermill": {"duration": 0.1, "status": "completed"}}},
            {"id": "keep", "metadata": {"execution": {"iopub.status.busy": "t"}}},
        ],
    }
    reporting.strip_volatile(nb)
    assert nb["metadata"]["papermill"] == {"parameters": {"a": 1}}
    assert nb["cells"][0]["id"] == "injected-parameters"
    assert nb["cells"][0]["metadata"]["papermill"] == {"status": "completed"}
    assert nb["cells"][1] == {"id": "keep", "metadata": {}}


def test_cleaning_repairs_keeps_only_repaired_sensors():
    qc = pd.DataFrame(
        {
            "run": ["E1", "E1", "E2"],
            "sensor": ["T1", "T2", "T1"],
            "source": ["box"] * 3,
            "n_raw": [100, 100, 100],
            "n_duplicates": [0, 1, 0],
            "n_out_of_range": [0, 0, 0],
            "n_spikes": [0, 2, 0],
            "n_interpolated": [0, 3, 0],
            "n_edge_held": [0, 0, 0],
            "n_long_gap": [0, 0, 0],
        }
    )
    repairs = reporting.cleaning_repairs(qc)
    assert repairs[["run", "sensor", "repaired"]].values.tolist() == [["E1", "T2", 6]]
    with pytest.raises(ValueError, match="n_spikes"):
        reporting.cleaning_repairs(qc.drop(columns=["n_spikes"]))


def test_table_html_formats_numbers_blanks_missing_and_escapes_text():
    frame = pd.DataFrame({"name": ["<T1>", "T2"], "value": [1.23456, float("nan")], "n": [3, 4]})
    text = reporting.table_html(frame, "%.2f", caption="A & B", max_rows=1)
    assert "<caption>A &amp; B</caption>" in text
    assert '<td>&lt;T1&gt;</td><td class="tx-num">1.23</td><td class="tx-num">3</td>' in text
    assert "T2" not in text and "First 1 of 2 rows" in text
    assert '<td class="tx-num"></td>' in reporting.table_html(frame.iloc[1:], "%.2f")


def test_figure_html_embeds_the_bytes():
    png = b"\x89PNG\r\n\x1a\nnot really a picture"
    text = reporting.figure_html(png, caption="Fig. `x`")
    uri = re.search(r'src="data:image/png;base64,([^"]+)"', text).group(1)
    assert base64.b64decode(uri) == png
    assert "<figcaption>Fig. <code>x</code></figcaption>" in text


def test_banner_flags_simulated_and_measured_data():
    simulated = reporting.banner_html("Report", "Dataset `twin`: SIMULATED data.", True)
    measured = reporting.banner_html("Report", "Dataset `lab`: measured data.", False)
    assert "SIMULATED DATA" in simulated and "Dataset <code>twin</code>: SIMULATED data." in simulated
    assert "MEASURED DATA" in measured and "SIMULATED" not in measured


def test_index_page_links_and_states_the_data():
    sections = [
        reporting.IndexSection("Reports", (reporting.IndexRow("paper", (("html", "reports/paper_report.html"),)),)),
        reporting.IndexSection("Empty", ()),
    ]
    page = reporting.render_index("twin", "Dataset `twin`: SIMULATED data.", True, sections)
    assert '<a href="reports/paper_report.html">html</a>' in page
    assert page.index("SIMULATED DATA") < page.index("<h2>Reports</h2>")
    assert "<h2>Empty</h2>" not in page
    assert reporting.remote_loads(page) == []


# --------------------------------------------------------------------------- end to end


@dataclass(frozen=True)
class Built:
    work: Path
    out: Path
    dataset: Path
    config: Path
    env: dict


_BUILD: dict[str, Built] = {}


def snakemake(built: Built, *args, check=True) -> subprocess.CompletedProcess:
    return run_snakemake(built.work, "--configfile", str(built.config), *args, check=check, env=built.env)


def build_reports(tmp_path_factory) -> Built:
    """The workflow on a small simulated dataset, once per test session (the browser test reuses it)."""
    if "built" not in _BUILD:
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
        env = snakemake_env()
        built = Built(work=work, out=work / "results" / "rep", dataset=dataset, config=config, env=env)
        snakemake(built)
        _BUILD["built"] = built
    return _BUILD["built"]


@pytest.fixture(scope="session")
def built(tmp_path_factory):
    return build_reports(tmp_path_factory)


def report_pages(out: Path) -> list[Path]:
    names = ["paper_report", "dataset_report", "condition_R1", "condition_R2"]
    names += [f"model_R2_{approach}_mlr" for approach in ("decoupled", "pointwise")]
    return [out / "reports" / f"{n}.html" for n in names]


@pytest.mark.slow
def test_every_report_and_the_index_are_built(built):
    for page in report_pages(built.out):
        assert page.is_file(), page
        assert page.with_suffix(".ipynb").is_file(), page
    assert (built.out / "index.html").is_file()
    assert sorted(p.name for p in (built.out / "reports").glob("model_*.html")) == [
        "model_R2_decoupled_mlr.html",
        "model_R2_pointwise_mlr.html",
    ]


@pytest.mark.slow
def test_first_screen_says_the_data_are_simulated(built):
    for page in report_pages(built.out):
        text = page.read_text(encoding="utf-8")
        body = text[text.index("<body") :]
        first_content = min(body.find(tag) for tag in ("<table", "<img", "<h2") if tag in body)
        banner = body.index('class="tx-banner')
        assert banner < first_content, page.name
        first_screen = body[banner:first_content]
        assert "SIMULATED DATA" in first_screen and "Dataset <code>rep</code>: SIMULATED data" in first_screen, page.name


@pytest.mark.slow
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
            assert not pattern.search(text), (page.name, what, pattern.search(text).group(0))
        assert "<script src" not in text, page.name


@pytest.mark.slow
def test_executed_notebooks_keep_outputs_but_no_time_stamps(built):
    for page in report_pages(built.out):
        nb = nbformat.read(page.with_suffix(".ipynb"), as_version=4)
        assert "start_time" not in nb.metadata["papermill"]
        assert all("execution" not in c.metadata for c in nb.cells)
        assert any(c.get("outputs") for c in nb.cells if c.cell_type == "code")
        injected = [c for c in nb.cells if "injected-parameters" in c.metadata.get("tags", [])]
        assert [c.id for c in injected] == ["injected-parameters"]


@pytest.mark.slow
def test_provenance_json_records_code_config_data_and_software(built):
    record = json.loads((built.out / "provenance.json").read_text(encoding="utf-8"))
    assert set(provenance.REQUIRED_KEYS) <= set(record)
    files = record["data"]["files"]
    on_disk = sorted(p.relative_to(built.dataset).as_posix() for p in built.dataset.rglob("*") if p.is_file())
    assert sorted(files) == on_disk
    assert files["runs.tsv"] == hashlib.sha256((built.dataset / "runs.tsv").read_bytes()).hexdigest()
    assert files["R2/errors/M03.csv"] == hashlib.sha256((built.dataset / "R2/errors/M03.csv").read_bytes()).hexdigest()
    assert record["config"]["selection"]["n_clusters"] == 2
    canonical = json.dumps(record["config"], sort_keys=True, separators=(",", ":")).encode()
    assert record["config_sha256"] == hashlib.sha256(canonical).hexdigest()
    assert record["run_time"] == "2023-11-14T22:13:20Z"
    assert record["python"]["version"] == ".".join(map(str, sys.version_info[:3]))
    if shutil.which("git"):
        head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True)
        if head.returncode == 0:
            assert record["git"]["commit"] == head.stdout.strip()


@pytest.mark.slow
def test_index_links_every_report_figure_and_table(built):
    index = built.out / "index.html"
    hrefs = re.findall(r'<a href="([^"]+)"', index.read_text(encoding="utf-8"))
    targets = {(index.parent / unquote(urlparse(h).path)).resolve() for h in hrefs}
    assert all(t.is_file() for t in targets), [str(t) for t in targets if not t.is_file()]
    expected = {p.resolve() for p in report_pages(built.out)}
    expected |= {p.resolve() for p in (built.out / "figures").iterdir()}
    expected |= {(built.out / "tables" / n).resolve() for n in ("metrics.csv", "paper_comparison.md", "table5_slope_intercept.csv")}
    assert expected <= targets, sorted(str(p) for p in expected - targets)
    assert (built.out / "provenance.json").resolve() in targets


def planned_rules(proc: subprocess.CompletedProcess) -> set[str]:
    return set(re.findall(r"^(?:local)?rule (\w+):", proc.stdout + proc.stderr, flags=re.M)) - {"all"}


@pytest.mark.slow
def test_nothing_reruns_and_a_rebuilt_report_is_byte_identical(built):
    assert planned_rules(snakemake(built, "-n")) == set()
    page = built.out / "reports" / "dataset_report.html"
    before = page.read_bytes(), page.with_suffix(".ipynb").read_bytes()
    snakemake(built, "--forcerun", "dataset_report", "--until", "dataset_report")
    assert (page.read_bytes(), page.with_suffix(".ipynb").read_bytes()) == before


@pytest.mark.slow
def test_changing_n_clusters_reruns_only_the_affected_reports(built):
    changed = built.work / "n_clusters_3.yaml"
    doc = yaml.safe_load(built.config.read_text())
    doc["selection"]["n_clusters"] = 3
    changed.write_text(yaml.safe_dump(doc))
    proc = run_snakemake(built.work, "-n", "--configfile", str(changed), check=False, env=built.env, timeout=300)
    rules = planned_rules(proc)
    assert {"select_sensitive_points", "model_report", "paper_report", "provenance", "index"} <= rules, rules
    assert not rules & {"dataset_report", "condition_report", "clean_run", "assemble", "fig5_unzeroed"}, rules
