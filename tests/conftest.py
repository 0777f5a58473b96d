"""Fixtures and the pytest-xdist hooks. The shared builders and truth are in ``helpers``."""

from __future__ import annotations

import os
import zlib

import pytest

from helpers.builders import write_dataset
from helpers.runs import Built, Run, make_built, make_lines_run


def pytest_configure(config):
    """One BLAS thread per test process, as a workflow job on one core has
    (thermaxis.pipeline.runner): `make test` runs a process per core, and OpenBLAS threads
    beside them would only wait for one another on the tests' small systems."""
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1, user_api="blas")


# The tiers that need something outside Python (marks of pyproject.toml). .ci/run names in
# THERMAXIS_REQUIRE_TIERS the ones it installed; there a skip of such a test is a failure.
TIERS = ("browser", "slurm", "mount")


def required_tiers() -> set[str]:
    names = {t.strip() for t in os.environ.get("THERMAXIS_REQUIRE_TIERS", "").split(",")}
    unknown = names - set(TIERS) - {""}
    if unknown:
        raise pytest.UsageError(f"THERMAXIS_REQUIRE_TIERS: unknown tier(s) {sorted(unknown)}")
    return names & set(TIERS)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if not report.skipped or hasattr(report, "wasxfail"):
        return
    tiers = {m.name for m in item.iter_markers() if m.name in TIERS} & required_tiers()
    if tiers:
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else report.longrepr
        report.outcome = "failed"
        report.longrepr = (
            f"the {', '.join(sorted(tiers))} tier was installed (THERMAXIS_REQUIRE_TIERS) "
            f"but its test skipped: {reason}"
        )


@pytest.fixture
def tiny_dataset(tmp_path):
    return write_dataset(tmp_path / "tiny")


@pytest.fixture(scope="session")
def lines_run(tmp_path_factory) -> Run:
    """The whole workflow (target ``all``: tables, figures, compensation, reports) once per
    session on three runs of five measurements whose errors are exact lines.

    Tests read it or dry-run against it (`-n`); only test_sweep_workflow adds to it, the
    ``sweep/`` folder of the `sweep` target, which `all` does not make.
    """
    return make_lines_run(tmp_path_factory.mktemp("lines"))


@pytest.fixture(scope="session")
def built(tmp_path_factory) -> Built:
    """The workflow with every kind of report on a small simulated dataset that reproduces
    the paper, once per test session (the reports and the browser tests read it)."""
    return make_built(tmp_path_factory.mktemp("reports"))


# --------------------------------------------------------------------------- pytest-xdist

# Test files whose tests share one expensive session fixture. `make test` runs pytest-xdist
# workers with ``--dist loadgroup``: each group below goes to one worker, which builds the
# run once (session fixtures are per worker), and every other file is a unit of its own.
# (xdist 3.8's own loadgroup marks do not group under pytest 9, which no longer reads the
# node id xdist rewrites; the scheduler below groups by file instead.)
SHARED_RUN_FILES = {
    "tests/slurm/test_slurm_workflow.py": "slurm",
    "tests/workflow/test_workflow.py": "lines_run",
    "tests/workflow/test_compensation_workflow.py": "lines_run",
    "tests/workflow/test_docs_workflow.py": "lines_run",
    "tests/workflow/test_interrupted_run.py": "lines_run",
    "tests/workflow/test_sweep_workflow.py": "lines_run",
    "tests/workflow/test_cli_workflow.py": "lines_run",
    "tests/workflow/test_conditions_report.py": "lines_run",
    "tests/workflow/test_reports.py": "built",
    "tests/workflow/test_browser.py": "built",
}
# The longest units start first, roughly longest first (the shared runs and the files of
# cold runs of their own, then the catalogue's units and the slowest files of the library's
# tests), so that no long unit is left alone at the end. (Each worker holds two units
# queued, so a unit is committed to a worker one unit ahead.)
_FIRST = (
    "tests/workflow/test_make_results.py",
    "lines_run",
    "slurm",
    "built",
    "tests/workflow/test_kernels.py",
    "tests/workflow/test_make_targets.py",
    "tests/workflow/test_machine_faults.py",
    "tests/workflow/test_measured_shapes.py",
    "tests/workflow/test_real_record.py",
    "tests/unit/test_structured_text.py",
    "tests/workflow/test_bad_input_catalogue.py",
    "tests/unit/test_plotting.py",
)
# Files of many independent cases, dealt out in this many units so that both workers share
# them (each unit makes the file's module fixtures once).
SPLIT_FILES = {"tests/workflow/test_bad_input_catalogue.py": 8}


def _unit_of(nodeid: str) -> str:
    path, _, test = nodeid.partition("::")
    if path in SPLIT_FILES:
        return f"{path}#{zlib.crc32(test.encode()) % SPLIT_FILES[path]}"
    return SHARED_RUN_FILES.get(path, path)


def pytest_collection_modifyitems(config, items):
    """The shared runs' files first; a test using a shared run outside its group is an error."""
    for item in items:
        for fixture in ("lines_run", "built"):
            if fixture in getattr(item, "fixturenames", ()) and _unit_of(item.nodeid) != fixture:
                raise pytest.UsageError(
                    f"{item.nodeid} uses {fixture}: list its file in conftest.SHARED_RUN_FILES"
                )
    rank = {group: i for i, group in enumerate(_FIRST)}

    def first(item) -> int:
        unit = _unit_of(item.nodeid)
        return rank.get(unit, rank.get(unit.partition("#")[0], len(rank)))

    items.sort(key=first)


def pytest_xdist_make_scheduler(config, log):
    if config.getoption("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class SharedRunScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return _unit_of(nodeid)

    config.option.loadscopereorder = False  # keep the collection order: shared runs first
    return SharedRunScheduling(config, log)
