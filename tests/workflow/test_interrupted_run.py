"""Recovery (issue 13): a workflow killed with SIGKILL completes on a plain rerun of the
``make results`` recipe (``python -m thermaxis.pipeline.resume snakemake ...``), with results
byte-identical to a run that was never interrupted; a live run is never disturbed.

The run that is never interrupted is the session's ``lines_run``; the killed run starts
cold in a folder of its own, so every one of its files is made afresh there, and the
comparison also shows that two cold runs give the same bytes.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

from helpers.workflow import SNAKEMAKE, snakemake_env, workflow_workdir

# Waiting for the killed run to reach the middle of the workflow; a bound, not a measurement.
WAIT_S = 300


def _digests(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def _wait_for(path: Path, proc: subprocess.Popen) -> None:
    deadline = time.monotonic() + WAIT_S
    while not path.exists():
        assert proc.poll() is None, "the run ended before it could be interrupted"
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.2)


def test_sigkill_then_plain_rerun_completes_byte_identical(lines_run, tmp_path):
    work = workflow_workdir(tmp_path / "killed")
    config = Path(
        shutil.copy(lines_run.config, work / lines_run.config.name)
    )  # same dataset, same config
    # The make results recipe, with the test's cores and configuration.
    command = [
        sys.executable,
        "-m",
        "thermaxis.pipeline.resume",
        SNAKEMAKE,
        "--cores",
        "2",
        "--configfile",
        config.name,
    ]
    first = subprocess.Popen(command, cwd=work, env=snakemake_env(), start_new_session=True,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    try:
        _wait_for(work / "results" / "lines" / "assembled" / "errors.parquet", first)
        # A second start while the first runs is refused and changes nothing.
        second = subprocess.run(
            command, cwd=work, env=snakemake_env(), capture_output=True, text=True
        )
        assert second.returncode == 1
        assert f"is already running in {work}" in second.stderr
        assert first.poll() is None and list((work / ".snakemake" / "locks").glob("*.lock"))
    finally:
        os.killpg(first.pid, signal.SIGKILL)
        first.wait()
    assert list((work / ".snakemake" / "locks").glob("*.lock")), (
        "SIGKILL should leave Snakemake's lock behind"
    )

    rerun = subprocess.run(command, cwd=work, env=snakemake_env(), capture_output=True, text=True)
    assert rerun.returncode == 0, rerun.stderr[-3000:]
    assert "clearing the lock of an interrupted run" in rerun.stderr
    # test_sweep_workflow may have added the sweep target's folder to the reference run.
    ours = _digests(work / "results" / "lines")
    reference = {k: v for k, v in _digests(lines_run.out).items() if not k.startswith("sweep/")}
    assert ours.keys() == reference.keys()
    assert [name for name in ours if ours[name] != reference[name]] == []
    assert any(name.endswith(".png") for name in ours) and any(
        name.endswith(".pdf") for name in ours
    )
