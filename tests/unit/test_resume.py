"""thermaxis.pipeline.resume: which processes count as a live Snakemake, which files are orphaned."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from thermaxis.pipeline import resume


@pytest.mark.parametrize(
    "argv, expected",
    [
        (["/x/.venv/bin/python3.11", "/x/.venv/bin/snakemake", "--cores", "2"], True),
        (["snakemake", "-n"], True),
        (["/usr/bin/python3", "/x/.venv/bin/snakemake"], True),
        (["python3", "-m", "snakemake", "--cores", "1"], True),
        # make's shell and this wrapper name snakemake without being it.
        (
            [
                "/bin/bash",
                "-c",
                ".venv/bin/python -m thermaxis.pipeline.resume .venv/bin/snakemake",
            ],
            False,
        ),
        (
            ["/x/.venv/bin/python", "-m", "thermaxis.pipeline.resume", "/x/.venv/bin/snakemake"],
            False,
        ),
        # A rule's script job.
        (["/x/.venv/bin/python", "/w/.snakemake/scripts/tmpab12.clean_run.py"], False),
        ([], False),
    ],
)
def test_only_snakemake_itself_counts(argv, expected):
    assert resume._is_snakemake(argv) is expected


def _fake_process(proc: Path, pid: int, argv: list[str], cwd: Path) -> None:
    entry = proc / str(pid)
    entry.mkdir(parents=True)
    (entry / "cmdline").write_bytes(b"\0".join(a.encode() for a in argv) + b"\0")
    os.symlink(cwd, entry / "cwd")


def test_live_snakemakes_are_those_in_this_folder(tmp_path):
    here, elsewhere, proc = tmp_path / "here", tmp_path / "elsewhere", tmp_path / "proc"
    here.mkdir()
    elsewhere.mkdir()
    _fake_process(proc, 11, ["python", "/v/bin/snakemake", "--cores", "2"], here)
    _fake_process(proc, 12, ["python", "/v/bin/snakemake"], elsewhere)
    _fake_process(proc, 13, ["bash", "-c", "snakemake"], here)
    (proc / "self").mkdir()
    assert resume.live_snakemakes(here, proc=proc) == [11]
    assert resume.live_snakemakes(elsewhere, proc=proc) == [12]


def test_orphaned_temporaries_match_atomic_writes_only(tmp_path):
    results = tmp_path / "results" / "twin" / "tables"
    results.mkdir(parents=True)
    orphans = [results / ".metrics.csv.k2j_9x0a.csv", results / ".errors.parquet.abcdefgh.parquet"]
    keep = [
        results / "metrics.csv",
        results / ".gitignore",
        results / ".metrics.csv.short.csv",
        results / ".a.csv.abcdefgh.png",
    ]
    for path in orphans + keep:
        path.write_text("x")
    assert resume.orphaned_temporaries(tmp_path / "results") == sorted(orphans)
    assert resume.orphaned_temporaries(tmp_path / "missing") == []
