"""thermaxis.pipeline.runner: each warning text reaches the terminal once; the log keeps all."""

from __future__ import annotations

import logging
import types

import pytest

from thermaxis.errors import DataError
from thermaxis.pipeline.runner import _configure_logging, run_script


def test_a_repeated_warning_is_printed_once_and_logged_every_time(tmp_path, capsys):
    log = tmp_path / "job.log"
    logger = _configure_logging(str(log))
    for _ in range(3):
        logger.warning("fold E4: hold on 2 of 9 cycles")
        # A Python warning, as logging.captureWarnings hands it over.
        logging.getLogger("py.warnings").warning(
            "x.py:3: UserWarning: no lambda-cut gives 6 classes"
        )
    logger.warning("another text")
    for handler in logging.getLogger("thermaxis").handlers:
        handler.flush()
    err = capsys.readouterr().err.splitlines()
    assert err == [
        "thermaxis warning: fold E4: hold on 2 of 9 cycles",
        "thermaxis warning: no lambda-cut gives 6 classes",
        "thermaxis warning: another text",
    ]
    text = log.read_text()
    assert text.count("hold on 2 of 9 cycles") == 3 and text.count("lambda-cut") == 3


def test_a_warning_another_job_reports_goes_to_this_jobs_log_only(tmp_path, capsys):
    import warnings

    from thermaxis.errors import SelectionWarning
    from thermaxis.pipeline.runner import log_only

    log = tmp_path / "job.log"
    with warnings.catch_warnings():
        # As in a job's own process: Python's warnings routed through logging from here.
        logging.captureWarnings(False)
        _configure_logging(str(log))
        warnings.simplefilter("always")
        with log_only(SelectionWarning):
            warnings.warn(
                "fold R1: only 2 distinct sensors were selected", SelectionWarning, stacklevel=1
            )
            warnings.warn("a warning of this job's own", UserWarning, stacklevel=1)
        warnings.warn(
            "fold R2: a selection warning outside the block", SelectionWarning, stacklevel=1
        )
    for handler in logging.getLogger("thermaxis").handlers:
        handler.flush()
    err = capsys.readouterr().err
    assert "only 2 distinct sensors" not in err
    assert "a warning of this job's own" in err and "outside the block" in err
    assert "SelectionWarning: fold R1: only 2 distinct sensors were selected" in log.read_text()
    logging.captureWarnings(False)


def _terminal(capsys) -> list[str]:
    """The lines the job's logging printed so far."""
    for handler in logging.getLogger("thermaxis").handlers:
        handler.flush()
    return capsys.readouterr().err.splitlines()


def test_a_solvers_convergence_warnings_reach_the_terminal_once_per_job(tmp_path, capsys):
    # A lasso's warning carries its duality gap, different at every fit: 3 texts, 1 line.
    log = tmp_path / "job.log"
    _configure_logging(str(log))
    for gap in ("4.1e-02", "3.5e-02", "1.9e-02"):
        logging.getLogger("py.warnings").warning(
            f"cd.py:7: ConvergenceWarning: Objective did not converge. Duality gap: {gap}"
        )
    # PLS's, with the component it stopped at: a solver's warning too.
    for k in (3, 4):
        logging.getLogger("py.warnings").warning(
            f"_pls.py:308: UserWarning: y residual is constant at iteration {k}"
        )
    logging.getLogger("thermaxis").warning("fold S3: another text")
    for handler in logging.getLogger("thermaxis").handlers:
        handler.flush()
    err = capsys.readouterr().err.splitlines()
    assert err == [
        "thermaxis warning: lasso: Objective did not converge. Duality gap: 4.1e-02 (the "
        f"first of this job's solver warnings; {log} has them all)",
        "thermaxis warning: fold S3: another text",
    ]
    assert log.read_text().count("Objective did not converge") == 3
    assert log.read_text().count("y residual is constant") == 2
    # The next job's first is PLS's: scikit-learn's text does not say which model it is.
    _configure_logging(str(tmp_path / "next.log"))
    logging.getLogger("py.warnings").warning(
        "_pls.py:308: UserWarning: y residual is constant at iteration 2"
    )
    assert _terminal(capsys) == [
        "thermaxis warning: PLS: y residual is constant at iteration 2 (the first of this "
        f"job's solver warnings; {tmp_path / 'next.log'} has them all)"
    ]
    # The Gaussian process's L-BFGS-B: its first line ends where scipy's reason begins.
    _configure_logging(str(tmp_path / "gp.log"))
    logging.getLogger("py.warnings").warning(
        "_optimize.py:445: ConvergenceWarning: lbfgs failed to converge after 19 "
        "iteration(s) (status=2):\nABNORMAL: \n\nIncrease the number of iterations."
    )
    assert _terminal(capsys) == [
        "thermaxis warning: Gaussian process: lbfgs failed to converge after 19 iteration(s) "
        f"(status=2) (the first of this job's solver warnings; {tmp_path / 'gp.log'} has them "
        "all)"
    ]
    logging.captureWarnings(False)


def _raise(exc: Exception):
    raise exc


def _job_with_log(path):
    return types.SimpleNamespace(log=[str(path)])


def test_a_value_error_is_one_line_on_the_terminal_and_its_traceback_is_in_the_log(
    tmp_path, capsys
):
    # A ValueError may be the code's, not the data's: where it was raised must not be lost.
    log = tmp_path / "job.log"
    message = "pls needs 1 <= n_components <= training rows, got 6"
    with pytest.raises(SystemExit):
        run_script(lambda _: _raise(ValueError(message)), _job_with_log(log))
    for handler in logging.getLogger("thermaxis").handlers:
        handler.flush()
    assert capsys.readouterr().err.splitlines() == [f"thermaxis error: {message}"]
    text = log.read_text()
    assert "Traceback" in text and "in _raise" in text
    # A data error is the data's: its one line is the whole story.
    data_log = tmp_path / "data.log"
    with pytest.raises(SystemExit):
        run_script(lambda _: _raise(DataError("x.csv: line 3: bad")), _job_with_log(data_log))
    assert "Traceback" not in data_log.read_text()


def _blas_threads() -> list[int]:
    from threadpoolctl import threadpool_info

    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


@pytest.mark.parametrize("threads", [1, 2])
def test_a_job_uses_at_most_its_snakemake_threads_for_blas(tmp_path, threads):
    import numpy  # noqa: F401  (loads the BLAS threadpoolctl reports)
    from threadpoolctl import threadpool_limits

    seen = []
    job = types.SimpleNamespace(log=[str(tmp_path / "job.log")], threads=threads)
    with threadpool_limits(limits=4, user_api="blas"):  # a machine of 4 cores, say
        before = _blas_threads()
        run_script(lambda _: seen.append(_blas_threads()), job)
        after = _blas_threads()
    assert before and set(before) == {4}
    assert seen == [[threads] * len(before)]
    assert after == before  # restored for whatever the process does next
    logging.captureWarnings(False)
