"""Recovery (issue 13): a workflow killed with SIGKILL completes on a plain rerun of the
``make results`` recipe (``python -m thermaxis.resume snakemake ...``), with results
byte-identical to a run that was never interrupted; a live run is never disturbed."""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from conftest import SNAKEMAKE, snakemake_env, workflow_workdir, write_dataset

pytestmark = pytest.mark.slow

# Waiting for the killed run to reach the middle of the workflow; a bound, not a measurement.
WAIT_S = 300


def _config(work: Path, dataset: Path) -> list[str]:
    config = {
        "dataset": str(dataset),
        "ambient_sensor": "S1",
        "selection": {"n_clusters": 2},
        "models": {"algorithms": ["mlr"]},
        "figures": {"algorithms": ["mlr"], "formats": ["png"]},
        "reports": {"model_algorithms": ["mlr"]},
    }
    (work / "run.yaml").write_text(yaml.safe_dump(config))
    # The make results recipe, with the test's cores and configuration.
    return [sys.executable, "-m", "thermaxis.resume", SNAKEMAKE, "--cores", "2", "--configfile", "run.yaml"]


def _digests(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(root.rglob("*")) if p.is_file()}


def _wait_for(path: Path, proc: subprocess.Popen) -> None:
    deadline = time.monotonic() + WAIT_S
    while not path.exists():
        assert proc.poll() is None, "the run ended before it could be interrupted"
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.2)


def test_sigkill_then_plain_rerun_completes_byte_identical(tmp_path):
    dataset = write_dataset(tmp_path / "kill", name="kill")
    clean = workflow_workdir(tmp_path / "clean")
    done = subprocess.run(_config(clean, dataset), cwd=clean, env=snakemake_env(), capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]

    work = workflow_workdir(tmp_path / "killed")
    command = _config(work, dataset)
    first = subprocess.Popen(command, cwd=work, env=snakemake_env(), start_new_session=True,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        _wait_for(work / "results" / "kill" / "assembled" / "errors.parquet", first)
        # A second start while the first runs is refused and changes nothing.
        second = subprocess.run(command, cwd=work, env=snakemake_env(), capture_output=True, text=True)
        assert second.returncode == 1
        assert f"is already running in {work}" in second.stderr
        assert first.poll() is None and list((work / ".snakemake" / "locks").glob("*.lock"))
    finally:
        os.killpg(first.pid, signal.SIGKILL)
        first.wait()
    assert list((work / ".snakemake" / "locks").glob("*.lock")), "SIGKILL should leave Snakemake's lock behind"

    rerun = subprocess.run(command, cwd=work, env=snakemake_env(), capture_output=True, text=True)
    assert rerun.returncode == 0, rerun.stderr[-3000:]
    assert "clearing the lock of an interrupted run" in rerun.stderr
    assert _digests(work / "results" / "kill") == _digests(clean / "results" / "kill")
