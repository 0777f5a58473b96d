"""The workflow through a real Slurm (tests/slurm/start_slurm.sh): a job killed with scancel
either fails the run cleanly or is resubmitted, and the completed run has a local run's bytes.

Skipped, with the reason, where the one-node cluster cannot be started (not root, the
Debian packages missing). The twin's models and a small sweep on the held-out run E4
keep each run short; the assembled tables they read are made locally first, so the
cluster runs the two rules that scancel and the job array are about (and the sweep's
collection), and the local reference run goes on beside them.

The cluster runs use .venv-slurm (`make slurm-env`: envs/requirements.txt plus the executor
plugin of envs/requirements-slurm.txt), the local run this test's own environment, which
has no executor plugin (docs/slurm-plugin-startup.md).
"""

from __future__ import annotations

import fcntl
import os
import re
import shutil
import subprocess
import time
from pathlib import Path

import pytest
import yaml

from helpers import REPO
from helpers.workflow import SNAKEMAKE, run_snakemake, snakemake_env, workflow_workdir

pytestmark = pytest.mark.slurm

START = REPO / "tests" / "slurm" / "start_slurm.sh"
# start_slurm.sh's state folder (its default, or THERMAXIS_SLURM_STATE as it reads it).
STATE = Path(os.environ.get("THERMAXIS_SLURM_STATE", "/var/lib/thermaxis-slurm"))
STOP = REPO / "tests" / "slurm" / "stop_slurm.sh"
SLURM_BIN = REPO / ".venv-slurm" / "bin"
TARGETS = (
    "results/twin/tables/metrics.csv",
    "results/twin/sweep/summary.csv",
    "results/twin/sweep/ranking.csv",
    "results/twin/sweep/factor_effects.csv",
)
SMALL_SVR = {"C": [1.0, 10.0], "epsilon": [0.1], "gamma": ["scale"]}
CONFIG = {
    "dataset": str(REPO / "data" / "raw" / "twin"),
    "folds": ["E4"],
    "models": {"algorithms": ["mlr", "svr"], "svr_grid": SMALL_SVR},
    "figures": {"formats": ["png"], "algorithms": ["mlr"]},
    "reports": {"model_algorithms": ["mlr"]},
    # 2 selection settings x (decoupled d1 + pointwise) x 2 algorithms = 8 evaluations of
    # fold E4: 1 batch locally on one core, 2 batches of 4 on the cluster.
    "sweep": {
        "methods": ["correlation", "fixed"],
        "n_clusters": [3],
        "degrees": [1],
        "algorithms": ["mlr", "svr"],
        "folds": ["E4"],
        "cluster_batch_size": 4,
    },
}


@pytest.fixture(scope="module")
def slurm():
    """The one-node cluster; stopped afterwards by the last test suite using it, if a test
    suite started it.

    Every suite holds a shared lock on the cluster's state folder while it runs. At the end,
    the suite that can take it exclusively is the last, and stops the cluster when a suite
    found it down (the mark ``started_by_tests``). A cluster that was running before any
    suite began is left running.
    """
    if os.geteuid() != 0:
        pytest.skip(
            "Slurm test: needs root to start the one-node cluster (tests/slurm/start_slurm.sh)"
        )
    STATE.mkdir(parents=True, exist_ok=True)
    mark = STATE / "started_by_tests"
    with open(STATE / "users.lock", "a") as users:
        fcntl.flock(users, fcntl.LOCK_SH)
        up = (
            shutil.which("scontrol") is not None
            and "UP" in subprocess.run(["scontrol", "ping"], capture_output=True, text=True).stdout
        )
        if not up:
            mark.touch()
        proc = subprocess.run(["bash", str(START)], capture_output=True, text=True, timeout=300)
        if proc.returncode != 0:
            reason = (proc.stderr.strip().splitlines() or ["no message"])[-1]
            if not up:
                mark.unlink()
            pytest.skip(f"Slurm test: the one-node cluster did not start: {reason}")
        yield
        try:
            fcntl.flock(users, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return  # another suite still uses it
        if mark.exists():
            subprocess.run(["bash", str(STOP)], capture_output=True, timeout=60)
            mark.unlink()


@pytest.fixture(scope="module")
def slurm_env(slurm) -> dict:
    """The environment of the cluster runs: .venv-slurm (made or brought up to date by
    `make slurm-env`) first on PATH; a failure to build it fails the tests."""
    proc = subprocess.run(["make", "--no-print-directory", "-C", str(REPO), "slurm-env"],
                          capture_output=True, text=True, timeout=1200)  # fmt: skip
    if proc.returncode != 0:
        pytest.fail(f"make slurm-env failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    env = snakemake_env()
    env["PATH"] = f"{SLURM_BIN}:{env['PATH']}"
    return env


def _workdir(tmp_path: Path) -> tuple[Path, Path]:
    work = workflow_workdir(tmp_path)
    os.symlink(REPO / "profiles", work / "profiles")
    config = work / "slurm_test_config.yaml"
    config.write_text(yaml.safe_dump(CONFIG))
    return work, config


def _slurm_command(config: Path, *extra: str) -> list[str]:
    # Status checks every 2 s instead of the profile's 20 s and Snakemake's 10 s: the jobs are short.
    return [
        str(SLURM_BIN / "snakemake"),
        "--profile",
        "profiles/slurm",
        "--nolock",
        "--configfile",
        str(config),
        "--slurm-init-seconds-before-status-checks",
        "2",
        "--seconds-between-status-checks",
        "2",
        "--latency-wait",
        "10",
        *extra,
        "--",
        *TARGETS,
    ]


def _results(work: Path) -> dict[str, bytes]:
    """Every result file by relative path; the batch files differ by design (batch count)."""
    root = work / "results" / "twin"
    return {
        str(p.relative_to(root)): p.read_bytes()
        for p in sorted(root.rglob("*"))
        if p.is_file() and "batches" not in p.relative_to(root).parts
    }


# What the cluster runs read, made locally in its work folder before it starts: the
# manifest, the cleaning and the assembly (run on the cluster they would only add three
# queued jobs in a row; their bytes are compared with the local run's all the same).
ASSEMBLED = "results/twin/assembled/errors.parquet"


@pytest.fixture
def local_run(slurm, tmp_path):
    """The local run of TARGETS on one core, started in the background: the cluster runs
    wait on the scheduler most of the time. Its process, log and work folder."""
    work, config = _workdir(tmp_path / "local")
    log = tmp_path / "local.log"
    command = [SNAKEMAKE, "--cores", "1", "--nolock", "--configfile", str(config), "--", *TARGETS]
    run = _start(work, command, log, snakemake_env())
    yield run, log, work
    if run.poll() is None:  # the test failed before it read the local results
        run.kill()
        run.wait()


def _local_results(run: subprocess.Popen, log: Path, work: Path) -> dict[str, bytes]:
    output = _finish(run, log)
    assert run.returncode == 0, output[-5000:]
    assert "thermaxis: sweep of 2 fold x selection units, 8 evaluations in 1 batches" in output
    assert (work / "results" / "twin" / "sweep" / "batches" / "1" / "0.parquet").is_file()
    return _results(work)


def _running_job(rule: str, log: Path, timeout: float = 300.0) -> str:
    """The Slurm id of the first RUNNING job of ``rule`` in the run logging to ``log``.

    The plugin names every job of a run after the run's id, which the log gives ("SLURM
    run ID: ..."), and puts the rule in the comment: another run's job on the same cluster
    is never taken for this one's.
    """
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        run = re.search(r"SLURM run ID: (\S+)", log.read_text())
        if run:
            out = subprocess.run(
                ["squeue", "-h", "-t", "RUNNING", "-n", run.group(1), "-o", "%i|%k"],
                capture_output=True,
                text=True,
            ).stdout
            for line in out.splitlines():
                job, _, comment = line.partition("|")
                if f"rule_{rule}" in comment:
                    return job.strip()
        time.sleep(0.5)
    raise AssertionError(f"no RUNNING Slurm job of rule {rule} of this run within {timeout:.0f} s")


def _start(work: Path, command: list[str], log: Path, env: dict) -> subprocess.Popen:
    # Output to a file, not a pipe: a full pipe would stall Snakemake while the test waits.
    with open(log, "w") as out:
        return subprocess.Popen(command, cwd=work, env=env, stdout=out, stderr=subprocess.STDOUT)


def _finish(run: subprocess.Popen, log: Path) -> str:
    run.wait(timeout=900)
    return log.read_text()


def test_scancel_fails_cleanly_then_resubmits_and_the_rerun_is_byte_identical_to_the_local_run(
    slurm_env, local_run, tmp_path
):
    """One cluster workflow serves three checks: a killed job fails a run without retries
    cleanly; with the profile's retries it is resubmitted; and the completed run, its sweep
    spread over a job array of two batches, has the local run's bytes."""
    work, config = _workdir(tmp_path / "cluster")
    run_snakemake(work, "--configfile", str(config), "--cores", "1", "--", ASSEMBLED)
    # 1. Without retries the killed job fails the run, with the job and its state named.
    # Only the models' table: the sweep's batches are left for the rerun to submit.
    first = _slurm_command(config, "--retries", "0")
    first = [*first[: first.index("--") + 1], TARGETS[0]]
    run = _start(work, first, tmp_path / "run.log", slurm_env)
    killed = _running_job("models", tmp_path / "run.log")
    subprocess.run(["scancel", killed], check=True)
    output = _finish(run, tmp_path / "run.log")
    assert run.returncode != 0
    assert f"SLURM-job '{killed}' failed, SLURM status is: 'CANCELLED'" in output
    assert "models" in output
    # The assembled tables were made before: the cluster ran the models' job alone.
    assert re.findall(r"^rule (\w+):", output, flags=re.M) == ["models"], output[-3000:]
    # Nothing half-written: the killed job's outputs are gone, no temporary file is left.
    fold_dir = work / "results" / "twin" / "models" / "E4"
    assert not (fold_dir.exists() and any(fold_dir.iterdir()))
    assert not [p for p in (work / "results").rglob(".*") if p.is_file()]

    # 2. The rerun, with the profile's retries: its models job is killed too,
    # resubmitted, and the run completes with the local run's bytes.
    rerun = _start(work, _slurm_command(config), tmp_path / "rerun.log", slurm_env)
    killed_again = _running_job("models", tmp_path / "rerun.log")
    subprocess.run(["scancel", killed_again], check=True)
    output = _finish(rerun, tmp_path / "rerun.log")
    assert rerun.returncode == 0, output[-5000:]
    assert f"SLURM-job '{killed_again}' failed, SLURM status is: 'CANCELLED'" in output
    assert "Trying to restart job" in output
    states = subprocess.run(["sacct", "-n", "-X", "-P", "-j", killed_again, "-o", "State"],
                            capture_output=True, text=True).stdout  # fmt: skip
    assert states.strip().startswith("CANCELLED")

    # 3. The cluster plan: the estimate before the start (8 evaluations x 0.065 s on 2
    # batches), the sweep's batches of 4 as one job array, and the local run's bytes.
    assert "SLURM run ID" in output
    assert "Submitted array job" in output
    assert "8 evaluations in 2 batches; estimated 0.00 CPU-hours at 0.065 s each" in output
    batches = sorted(
        p.name for p in (work / "results" / "twin" / "sweep" / "batches" / "2").iterdir()
    )
    assert batches == ["0.parquet", "1.parquet"]
    ours, theirs = _results(work), _local_results(*local_run)
    assert sorted(ours) == sorted(theirs)
    assert [name for name in ours if ours[name] != theirs[name]] == []
