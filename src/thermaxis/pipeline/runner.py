"""The edge between Snakemake scripts and the library.

Scripts stay thin: they call :func:`run_script`, which sends warnings and log
records to the rule's log file and turns a data problem into ONE line on stderr
instead of a traceback, so the user sees which file and what was expected.
"""

from __future__ import annotations

import errno
import logging
import os
import re
import sys
import tempfile
import warnings
from collections.abc import Mapping
from contextlib import contextmanager
from pathlib import Path

from thermaxis.errors import DataError

__all__ = ["run_script", "thread_pools", "atomic_path", "write_csv", "write_text"]


# A solver's warning differs in its numbers at every fit (LARS's dropped regressor, a
# GP's length scale at its bound, the PLS component after which the target has nothing
# left to fit), so text alone would not collapse it: a job shows its first one.
_PLS_EXHAUSTED = "y residual is constant at iteration"
_ONCE_PER_JOB = ("ConvergenceWarning: ", _PLS_EXHAUSTED)
# scikit-learn's texts do not say which model spoke: the terminal line does, where the
# text is one model's own.
_SOLVERS = (
    (_PLS_EXHAUSTED, "PLS"),
    ("parameter length_scale", "Gaussian process"),
    ("parameter constant_value", "Gaussian process"),
    ("parameter noise_level", "Gaussian process"),
    # scipy's L-BFGS-B, which only the Gaussian process's optimiser uses here.
    ("lbfgs failed to converge", "Gaussian process"),
    ("Objective did not converge", "lasso"),
    ("Regressors in active set degenerate", "lasso"),
    ("Solver terminated early", "SVR"),
)


def _solver_warning(message: str) -> bool:
    return any(marker in message for marker in _ONCE_PER_JOB)


def _solver_of(message: str) -> str:
    return next((f"{model}: " for marker, model in _SOLVERS if marker in message), "")


class _OneLine(logging.Formatter):
    """``thermaxis warning: <message>``; a captured Python warning loses its source location.

    A solver's warning names its model and the log (``log_path``) that has all of them."""

    _LOCATION = re.compile(r"^.*?:\d+: \w*Warning: ")

    def __init__(self, log_path: str | None = None):
        super().__init__()
        self._log = log_path or "the job's log"

    def format(self, record):
        first = record.getMessage().splitlines()[0] if record.getMessage() else ""
        # A first line that introduces the next ("...(status=2):") stands alone here.
        text = self._LOCATION.sub("", first).rstrip(":")
        if _solver_warning(first):
            text = (
                f"{_solver_of(first)}{text} (the first of this job's solver warnings; "
                f"{self._log} has them all)"
            )
        return f"thermaxis warning: {text}"


class _Once(logging.Filter):
    """Warnings only, each text once: a sweep repeats one warning per configuration, and
    the log file keeps every occurrence. A solver's convergence warnings once per job."""

    def __init__(self):
        super().__init__()
        self._seen: set[str] = set()

    def filter(self, record):
        if record.levelno != logging.WARNING:
            return False
        text = _OneLine().format(record)
        key = "solver" if _solver_warning(record.getMessage()) else text
        if key in self._seen:
            return False
        self._seen.add(key)
        return True


# The logger of what this job's log keeps but the terminal has from another job.
_LOG_ONLY = "thermaxis.log_only"


@contextmanager
def log_only(category: type[Warning]):
    """Warnings of ``category`` go to this job's log and not to the terminal.

    For a job that re-derives what another job reports: the statistics, the
    recommendation and the compensation select sensitive points again on the same folds,
    and the terminal has their selection's warnings from the models job already.
    """
    previous = warnings.showwarning
    log = logging.getLogger(_LOG_ONLY)

    def show(message, kind, filename, lineno, file=None, line=None):
        if issubclass(kind, category):
            log.warning("%s: %s", kind.__name__, message)
        else:
            previous(message, kind, filename, lineno, file, line)

    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = previous


def _configure_logging(log_path: str | None) -> logging.Logger:
    logger = logging.getLogger("thermaxis")
    py_warnings = logging.getLogger("py.warnings")
    # A second script in one process (the bad-input tests) closes the first one's log.
    for previous in {*logger.handlers, *py_warnings.handlers}:
        previous.close()
    logger.handlers.clear()
    logger.setLevel(logging.INFO)
    handler: logging.Handler
    if log_path:
        Path(log_path).parent.mkdir(parents=True, exist_ok=True)
        handler = logging.FileHandler(log_path, mode="w", encoding="utf-8")
    else:
        handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(levelname)s %(message)s"))
    # A warning only in a log file nobody opens is silence: the terminal gets it too
    # (errors reach it through run_script's one line).
    terminal = logging.StreamHandler(sys.stderr)
    terminal.setFormatter(_OneLine(log_path))
    terminal.addFilter(_Once())
    logger.addHandler(handler)
    log_only_logger = logging.getLogger(_LOG_ONLY)
    log_only_logger.handlers = [handler]
    log_only_logger.propagate = False
    logging.captureWarnings(True)
    py_warnings.handlers.clear()
    py_warnings.addHandler(handler)
    if log_path:
        logger.addHandler(terminal)
        py_warnings.addHandler(terminal)
    return logger


@contextmanager
def thread_pools(threads: int):
    """BLAS (OpenBLAS) and OpenMP use at most ``threads`` (a job's Snakemake ``threads``)
    in the libraries loaded so far.

    Snakemake runs other jobs on the cores it did not give this one, and OpenBLAS would
    otherwise start a thread per core in every job. On the pipeline's small systems the
    threads cost more than they share: waking them for each call of the Gaussian process's
    L-BFGS-B made a 24-row fit 2.4 times slower (31 against 13 ms).
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=max(1, int(threads))):
        yield


def run_script(main, snakemake) -> None:
    """Run ``main(snakemake)``; a :class:`DataError` or ``ValueError`` ends in one clear line."""
    log = snakemake.log[0] if len(snakemake.log) else None
    logger = _configure_logging(log)
    warnings.simplefilter("default")
    try:
        with thread_pools(getattr(snakemake, "threads", 1)):
            main(snakemake)
    except (DataError, ValueError) as exc:
        message = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        logger.error(message)
        if not isinstance(exc, DataError):
            # A ValueError may come from the code rather than the data: where it was
            # raised goes to the job's log (the terminal keeps its one line).
            logging.getLogger(_LOG_ONLY).error("raised at", exc_info=exc)
        print(f"thermaxis error: {message}", file=sys.stderr)
        sys.exit(1)
    except OSError as exc:
        if not machine_fault(exc):
            raise
        logger.exception("machine fault")
        print(f"thermaxis error: {fault_line(exc)}", file=sys.stderr)
        sys.exit(1)
    except Exception as exc:  # noqa: BLE001 - an unforeseen input must still end in one line
        logger.exception("unexpected error")
        first = str(exc).splitlines()[0] if str(exc) else ""
        print(
            f"thermaxis error: unexpected {type(exc).__name__}: {first} (traceback in {log or 'stderr'})",
            file=sys.stderr,
        )
        sys.exit(1)


# Faults of the machine, not of the data or the code: a full disk, a read-only folder.
_MACHINE_FAULTS = {
    errno.ENOSPC: "no space left on the device",
    errno.EDQUOT: "disk quota exceeded",
    errno.EROFS: "read-only file system",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
}


def machine_fault(exc: OSError) -> bool:
    """A full disk or a folder that cannot be written (pyarrow names ENOSPC in its text only)."""
    return exc.errno in _MACHINE_FAULTS or "No space left on device" in str(exc)


def fault_line(exc: OSError) -> str:
    """One line: the file, what the machine refused, and that nothing half-written was left."""
    cause = _MACHINE_FAULTS.get(exc.errno, "no space left on the device")
    where = f"{exc.filename}: " if exc.filename else ""
    return f"{where}{cause}; nothing half-written was left in its place: free space or fix the folder, then rerun"


@contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path`` and move it into place only on success.

    A machine fault while writing names ``path`` (a write's OSError names no file).
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    except OSError as exc:
        _raise_named(exc, path)
    os.close(fd)
    try:
        yield Path(tmp)
        # mkstemp creates 0600 files; results are meant to be read and served by others.
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except OSError as exc:
        _raise_named(exc, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _raise_named(exc: OSError, path: Path):
    """Re-raise ``exc``; a machine fault as an OSError that names ``path``."""
    if not machine_fault(exc):
        raise exc
    code = exc.errno if exc.errno in _MACHINE_FAULTS else errno.ENOSPC
    raise OSError(code, os.strerror(code), str(path)) from exc


def csv_text(frame, float_format: str = "%.6g") -> str:
    """CSV with explicit float format and Unix newlines, so reruns are byte-identical."""
    return frame.to_csv(index=False, float_format=float_format, lineterminator="\n")


def write_csv(frame, path, float_format: str = "%.6g") -> None:
    write_text(csv_text(frame, float_format), path)


def write_text(text: str, path) -> None:
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")


def write_texts(texts: Mapping) -> None:
    """Every file of a job, written only once all of them are computed: a job that stops
    half-way leaves none of its outputs behind."""
    for path, text in texts.items():
        write_text(text, path)


def write_parquet(frame, path) -> None:
    with atomic_path(path) as tmp:
        frame.to_parquet(tmp, index=False)
