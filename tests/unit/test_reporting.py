"""Reports, unit level: notebooks committed clean, provenance records, HTML helpers."""

from __future__ import annotations

import base64
import hashlib
import json
import os
import re
import shutil
import subprocess
import tempfile
from datetime import UTC, datetime
from pathlib import Path

import nbformat
import pandas as pd
import pytest

from helpers import REPO
from helpers.builders import held_out_summary
from helpers.workflow import FIXED_EPOCH
from thermaxis.compensation.verdict import deployment_verdict
from thermaxis.reports import html as rep
from thermaxis.reports import index as index_page
from thermaxis.reports import notebooks, provenance, summaries
from thermaxis.reports.crossdataset import model_ranking

NOTEBOOKS = ("dataset_report", "condition_report", "model_report", "paper_report")


# --------------------------------------------------------------------------- notebooks


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_notebook_is_committed_without_outputs_and_has_a_parameters_cell(name):
    nb = nbformat.read(REPO / "notebooks" / f"{name}.ipynb", as_version=4)
    nbformat.validate(nb)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert all(c.outputs == [] and c.execution_count is None for c in code), (
        f"{name}: clear the outputs before committing"
    )
    tagged = [c for c in code if "parameters" in c.metadata.get("tags", [])]
    assert len(tagged) == 1 and tagged[0] is code[0], (
        f"{name}: the first code cell must be the only one tagged 'parameters'"
    )
    assert nb.metadata["kernelspec"]["name"] == "python3"
    assert "papermill" not in nb.metadata


# --------------------------------------------------------------------------- provenance


def test_sha256_of_a_known_file(tmp_path):
    path = tmp_path / "abc.txt"
    path.write_bytes(b"abc")
    # FIPS 180-2 test vector for "abc".
    assert (
        provenance.sha256_file(path)
        == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    )


def test_manifest_hashes_every_file_and_matches_sha256sum(tmp_path):
    (tmp_path / "R1" / "errors").mkdir(parents=True)
    (tmp_path / "runs.tsv").write_bytes(b"run\n")
    (tmp_path / "R1" / "errors" / "M01.csv").write_bytes(b"abc")
    (tmp_path / "R1" / "notes.txt").write_bytes(b"")
    manifest = provenance.data_manifest(tmp_path)
    assert list(manifest) == ["R1/errors/M01.csv", "R1/notes.txt", "runs.tsv"]
    assert (
        manifest["R1/errors/M01.csv"]
        == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    )
    # SHA-256 of the empty string (FIPS 180-2).
    assert (
        manifest["R1/notes.txt"]
        == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
    )
    # The hash of `sha256sum`'s listing, whose line format is "<hex digest>, two spaces, name".
    listing = "".join(
        f"{hashlib.sha256((tmp_path / name).read_bytes()).hexdigest()}  {name}\n"
        for name in ("R1/errors/M01.csv", "R1/notes.txt", "runs.tsv")
    ).encode()
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
    assert (
        provenance.run_time(datetime(2024, 2, 29, 12, 0, 5, tzinfo=UTC)) == "2024-02-29T12:00:05Z"
    )


@pytest.mark.skipif(shutil.which("git") is None, reason="git is not installed")
def test_git_state_commit_and_dirty_flag(tmp_path):
    repo = tmp_path / "repo"
    repo.mkdir()
    env = {
        **os.environ,
        "GIT_AUTHOR_NAME": "t",
        "GIT_AUTHOR_EMAIL": "t@t",
        "GIT_COMMITTER_NAME": "t",
        "GIT_COMMITTER_EMAIL": "t@t",
    }

    def git(*args):
        return subprocess.run(
            ["git", "-C", str(repo), *args], capture_output=True, text=True, check=True, env=env
        ).stdout

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
    record = provenance.collect(
        tmp_path, {"b": 1, "a": {"x": 2}}, tmp_path, git={"commit": "c0ffee", "dirty": False}
    )
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
        '<img src="data:image/png;base64,AAAA"><link rel="icon" href="data:,">'
        '<a href="../index.html">i</a>'
    )
    found = notebooks.remote_loads(page)
    assert len(found) == 5
    assert not any("doi.org" in f for f in found)


def test_a_page_shows_outputs_and_markdown_with_each_html_output_focusable():
    png = b"\x89PNG"
    figure = rep.figure_html(png, "Fig. 1", alt="the figure")
    nb = nbformat.v4.new_notebook(
        cells=[
            nbformat.v4.new_markdown_cell("## Section *one*"),
            nbformat.v4.new_code_cell(
                "secret_input()",
                outputs=[
                    nbformat.v4.new_output(
                        "display_data", data={"text/html": f"<p>first</p>{figure}"}
                    ),
                    nbformat.v4.new_output("display_data", data={"text/html": "<p>second</p>"}),
                ],
            ),
        ]
    )
    page = notebooks.notebook_to_html(nb, "A title")
    assert "<title>A title</title>" in page
    assert re.search(r"<h2[^>]*>Section <em>one</em>", page)
    assert "secret_input" not in page  # code hidden
    outputs = re.findall(r'<div class="[^"]*jp-OutputArea-output[^"]*"[^>]*>', page)
    assert len(outputs) == 2 and all('tabindex="0"' in div for div in outputs)
    assert re.findall(r"<img [^>]*>", page) == [
        f'<img src="data:image/png;base64,{base64.b64encode(png).decode()}" alt="the figure">'
    ]


def test_strip_volatile_drops_time_stamps_and_fixes_the_injected_cell_id():
    nb = {
        "metadata": {
            "papermill": {
                "start_time": "t0",
                "end_time": "t1",
                "duration": 1.5,
                "parameters": {"a": 1},
            }
        },
        "cells": [
            {
                "id": "random-uuid",
                "metadata": {
                    "tags": ["injected-parameters"],
                    "papermill": {"duration": 0.1, "status": "completed"},
                },
            },
            {"id": "keep", "metadata": {"execution": {"iopub.status.busy": "t"}}},
        ],
    }
    notebooks.strip_volatile(nb)
    assert nb["metadata"]["papermill"] == {"parameters": {"a": 1}}
    assert nb["cells"][0]["id"] == "injected-parameters"
    assert nb["cells"][0]["metadata"]["papermill"] == {"status": "completed"}
    assert nb["cells"][1] == {"id": "keep", "metadata": {}}


def _python_notebook(nb, path):
    """``nb`` written to ``path`` for the python3 kernel."""
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "language": "python",
        "display_name": "Python 3",
    }
    nbformat.write(nb, path)
    return path


def test_pages_share_one_kernel_but_not_its_names(tmp_path):
    """Three pages of one notebook in one kernel: each sees its own parameter, none sees a
    name the page before defined (an underscored one neither), and each counts its cells
    from 1 as a fresh kernel does."""
    nb = nbformat.v4.new_notebook(
        cells=[
            nbformat.v4.new_code_cell("x = 0", metadata={"tags": ["parameters"]}),
            nbformat.v4.new_code_cell(
                "print(x, 'left' in dir(), '_left' in dir())\nleft = _left = x"
            ),
            nbformat.v4.new_code_cell("x * 10"),
        ]
    )
    source = _python_notebook(nb, tmp_path / "page.ipynb")
    pages = [
        dict(executed=tmp_path / f"p{i}.ipynb", html=tmp_path / f"p{i}.html", title=f"page {i}",
             parameters={"x": i})
        for i in (1, 2, 3)
    ]  # fmt: skip
    notebooks.execute_pages(source, pages)
    for i, page in enumerate(pages, start=1):
        done = nbformat.read(page["executed"], as_version=4)
        code = [c for c in done.cells if c.cell_type == "code"]
        # The parameters cell, papermill's injected cell, then the notebook's two cells.
        assert [c.execution_count for c in code] == [1, 2, 3, 4]
        assert code[2].outputs[0]["text"] == f"{i} False False\n"
        assert code[3].outputs[0]["data"]["text/plain"] == str(10 * i)
        assert code[3].outputs[0]["execution_count"] == 4
        assert f"page {i}" in page["html"].read_text(encoding="utf-8")


@pytest.mark.parametrize("temporary", ["system", "deep"])
def test_a_page_runs_in_a_kernel_on_private_socket_files_that_go_with_it(
    temporary, tmp_path, monkeypatch
):
    """No TCP port another process could take between its choice and the kernel's bind: the
    kernel reports IPC transport, its connection file in a folder removed after the page.
    Under a temporary folder too deep for a socket's path (108 bytes on Linux), as a
    cluster job's TMPDIR can be, the folder goes under /tmp instead."""
    if temporary == "deep":
        deep = tmp_path / ("d" * 120)
        deep.mkdir()
        monkeypatch.setattr(tempfile, "tempdir", str(deep))
    nb = nbformat.v4.new_notebook(
        cells=[
            nbformat.v4.new_code_cell(
                "import json\nfrom ipykernel.connect import get_connection_file, get_connection_info\n"
                "print(json.loads(get_connection_info())['transport'])\nprint(get_connection_file())"
            )
        ]
    )
    source = _python_notebook(nb, tmp_path / "page.ipynb")
    executed = tmp_path / "done.ipynb"
    notebooks.execute(source, executed, tmp_path / "done.html", "one page", {})
    transport, connection = (
        nbformat.read(executed, as_version=4).cells[-1].outputs[0]["text"].split()
    )
    assert transport == "ipc"
    assert Path(connection).name == "connection.json" and not Path(connection).parent.exists()
    assert len(os.fsencode(Path(connection).parent / "socket-99999")) < 108
    assert "one page" in (tmp_path / "done.html").read_text(encoding="utf-8")


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
    repairs = summaries.cleaning_repairs(qc)
    assert repairs[["run", "sensor", "repaired"]].values.tolist() == [["E1", "T2", 6]]
    with pytest.raises(ValueError, match="n_spikes"):
        summaries.cleaning_repairs(qc.drop(columns=["n_spikes"]))


def test_table_html_formats_numbers_blanks_missing_and_escapes_text():
    frame = pd.DataFrame({"name": ["<T1>", "T2"], "value": [1.23456, float("nan")], "n": [3, 4]})
    text = rep.table_html(frame, "%.2f", caption="A & B", max_rows=1)
    assert "<caption>A &amp; B</caption>" in text
    assert '<td>&lt;T1&gt;</td><td class="tx-num">1.23</td><td class="tx-num">3</td>' in text
    assert "T2" not in text and "First 1 of 2 rows" in text
    assert '<td class="tx-num"></td>' in rep.table_html(frame.iloc[1:], "%.2f")


def test_figure_html_embeds_the_bytes():
    png = b"\x89PNG\r\n\x1a\nnot really a picture"
    text = rep.figure_html(png, caption="Fig. `x`")
    uri = re.search(r'src="data:image/png;base64,([^"]+)"', text).group(1)
    assert base64.b64decode(uri) == png
    assert "<figcaption>Fig. <code>x</code></figcaption>" in text


def test_banner_flags_simulated_and_measured_data():
    simulated = rep.banner_html("Report", "Dataset `twin`: SIMULATED data.", True)
    measured = rep.banner_html("Report", "Dataset `lab`: measured data.", False)
    assert (
        "SIMULATED DATA" in simulated and "Dataset <code>twin</code>: SIMULATED data." in simulated
    )
    assert "MEASURED DATA" in measured and "SIMULATED" not in measured


def test_index_page_links_and_states_the_data():
    sections = [
        index_page.IndexSection(
            "Reports", (index_page.IndexRow("paper", (("html", "reports/paper_report.html"),)),)
        ),
        index_page.IndexSection("Empty", ()),
    ]
    metrics = pd.DataFrame(
        {
            "fold": ["E1"],
            "approach": ["decoupled"],
            "algorithm": ["mlr"],
            "target": ["error"],
            "rmse": [1.0],
            "max_abs": [2.0],
        }  # fmt: skip
    )
    verdict = deployment_verdict(held_out_summary([("R1", 1, 2.0, 1.0, 1.0, 0.5)]), 0.1, 0.05)
    deployment = {"candidate": "x", "model": "recommended", "verdict": verdict}
    headline = index_page.Headline(model_ranking(metrics), "Recommended: x.", deployment)
    page = index_page.render_index(
        "twin", "Dataset `twin`: SIMULATED data.", True, headline, sections=sections
    )
    assert '<a href="reports/paper_report.html">html</a>' in page
    assert page.index("SIMULATED DATA") < page.index("<h2>Reports</h2>")
    assert "<h2>Empty</h2>" not in page
    assert notebooks.remote_loads(page) == []


def test_only_the_paper_twin_is_said_to_be_calibrated_to_the_paper():
    from thermaxis.dataset.summary import data_statement

    assert data_statement("twin", True) == (
        "Dataset `twin`: SIMULATED data (thermal twin calibrated to the paper's fits and results), "
        "not the paper's measurements."
    )
    assert data_statement("scale", True, "thermaxis.twin scale", reproduces_paper=False) == (
        "Dataset `scale`: SIMULATED data, not measurements of a machine. Source: thermaxis.twin scale"
    )
    assert data_statement("rig", False, "") == "Dataset `rig`: MEASURED data."
