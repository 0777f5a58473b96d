"""Faults of the machine the workflow runs on: a full disk, folders that cannot be written,
two runs at once in two clones of one dataset.

Each fault leaves nothing half-written, and a plain rerun (``python -m
thermaxis.pipeline.resume snakemake ...``, the ``make results`` recipe) finishes the job.
The faults are made for real: a small tmpfs as the results folder, read-only bind mounts.
That needs root (or CAP_SYS_ADMIN) and a container that permits mounts; elsewhere the
tests skip and say why. Root ignores permission bits, so a folder is made read-only by a
read-only bind mount, never by chmod.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path

import pandas as pd
import pytest

from helpers.builders import write_dataset
from helpers.workflow import SNAKEMAKE, snakemake_env, tiny_config, workflow_workdir

TARGET = "results/tiny/tables/cleaning_qc.csv"
# Partial outputs of the first jobs as atomic_path names them while they are written.
TEMP_PREFIX = "."


def _mount(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(["mount", *args], capture_output=True, text=True)


def _umount(path: Path) -> None:
    subprocess.run(["umount", "-l", str(path)], capture_output=True)


def _skip_unless_mounted(proc: subprocess.CompletedProcess, what: str) -> None:
    if proc.returncode != 0:
        why = (proc.stderr or proc.stdout).strip().splitlines()
        pytest.skip(
            f"cannot mount {what} here ({why[-1] if why else 'mount failed'}; uid {os.getuid()})"
        )


@contextmanager
def tmpfs(path: Path, size: str):
    path.mkdir(parents=True, exist_ok=True)
    _skip_unless_mounted(_mount("-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)), "a tmpfs")
    try:
        yield path
    finally:
        _umount(path)


@contextmanager
def read_only(path: Path):
    """``path`` read-only for every user, root included: a read-only bind mount over itself."""
    _skip_unless_mounted(_mount("--bind", str(path), str(path)), "a bind mount")
    try:
        _skip_unless_mounted(_mount("-o", "remount,ro,bind", str(path)), "a read-only bind mount")
        yield path
    finally:
        _umount(path)


def _fill(folder: Path) -> Path:
    """A file that takes every free byte of ``folder``'s file system."""
    filler = folder / "filler"
    chunk = b"\0" * 65536
    with open(filler, "wb") as fh:
        try:
            while True:
                fh.write(chunk)
                fh.flush()
        except OSError:
            pass
    while True:  # the last partial chunk is still buffered: write it byte by byte until full
        try:
            with open(filler, "ab") as fh:
                fh.write(b"\0" * 512)
        except OSError:
            return filler


def _recipe(config: Path, *targets: str, cores: int = 2) -> list[str]:
    """The ``make results`` recipe for one dataset: resume, then Snakemake."""
    snakemake = [SNAKEMAKE, "--cores", str(cores), *targets, "--configfile", str(config)]
    return [sys.executable, "-m", "thermaxis.pipeline.resume", *snakemake]


def _snakemake(work: Path, config: Path, *targets: str, check: bool = True):
    proc = subprocess.run(
        _recipe(config, *targets),
        cwd=work,
        capture_output=True,
        text=True,
        env=snakemake_env(),
        timeout=900,
    )
    if check and proc.returncode != 0:
        raise AssertionError(f"run failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-5000:]}")
    return proc


def _errors(proc) -> list[str]:
    return [line for line in (proc.stdout + proc.stderr).splitlines() if "thermaxis error:" in line]


def _tree(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


@pytest.fixture
def tiny(tmp_path):
    dataset = write_dataset(tmp_path / "data" / "tiny", name="tiny")
    work = workflow_workdir(tmp_path)
    return work, dataset, tiny_config(work, dataset)


@pytest.mark.mount
def test_a_full_disk_is_one_line_naming_the_file_and_a_rerun_finishes(tiny):
    work, _, config = tiny
    with tmpfs(work / "results", "1m") as results:
        filler = _fill(results)
        proc = _snakemake(work, config, TARGET, check=False)
        assert proc.returncode != 0
        errors = _errors(proc)
        assert errors, proc.stderr[-3000:]
        for line in errors:
            assert "no space left on the device" in line and "results/tiny/" in line, line
            assert "Traceback" not in line and "unexpected" not in line, line
        # Nothing half-written: no temporary file, and every table in place reads whole.
        written = [p for p in results.rglob("*") if p.is_file() and p != filler]
        assert not [p for p in written if p.name.startswith(TEMP_PREFIX)], written
        for path in written:
            if path.suffix == ".csv":
                pd.read_csv(path)
            elif path.suffix == ".parquet":
                pd.read_parquet(path)
        filler.unlink()
        _snakemake(work, config, TARGET)
        qc = pd.read_csv(results / "tiny" / "tables" / "cleaning_qc.csv")
        assert sorted(qc["run"].unique()) == ["R1", "R2"]


@pytest.mark.mount
def test_read_only_results_are_one_line_before_any_job_a_read_only_dataset_no_matter(tiny):
    """The refused run, then the rerun that finishes with the results folder writable again,
    made with the dataset read-only: the jobs that read it (its manifest and the cleaning of
    every run) never write there."""
    work, dataset, config = tiny
    (work / "results").mkdir()
    with read_only(work / "results"):
        proc = _snakemake(work, config, TARGET, check=False)
        assert proc.returncode != 0
        errors = _errors(proc)
        assert len(errors) == 1, proc.stderr[-3000:]
        assert "results/tiny (its folder" in errors[0] and "read-only file system" in errors[0]
        assert "rule clean:" not in proc.stdout + proc.stderr  # no job started
    before = _tree(dataset)
    with read_only(dataset):
        _snakemake(work, config, TARGET)
    assert _tree(dataset) == before
    assert sorted(pd.read_csv(work / TARGET)["run"].unique()) == ["R1", "R2"]


def test_two_runs_in_two_clones_of_one_dataset_both_finish(tmp_path):
    dataset = write_dataset(tmp_path / "data" / "tiny", name="tiny")
    clones = [workflow_workdir(tmp_path / name) for name in ("a", "b")]
    configs = [tiny_config(work, dataset) for work in clones]
    # The jobs that read the shared dataset (its manifest, the cleaning) and the assembly
    # of what they wrote; the models after them read each clone's own results only.
    procs = [
        subprocess.Popen(
            _recipe(config, TARGET, cores=1),
            cwd=work,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env=snakemake_env(),
        )
        for work, config in zip(clones, configs, strict=True)
    ]
    outputs = [p.communicate(timeout=900)[0] for p in procs]
    assert [p.returncode for p in procs] == [0, 0], "\n".join(o[-3000:] for o in outputs)
    a, b = (_tree(work / "results" / "tiny") for work in clones)
    assert a == b
    assert sorted(pd.read_csv(clones[0] / TARGET)["run"].unique()) == ["R1", "R2"]
