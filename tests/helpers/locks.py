"""A lock over the library's source files, shared by the pytest-xdist workers."""

from __future__ import annotations

import fcntl
from contextlib import contextmanager


@contextmanager
def library_lock(tmp_path_factory, exclusive: bool = False):
    """A lock over the library's source files, shared by the pytest-xdist workers.

    A test that edits a module of src/thermaxis (and restores it) holds it exclusively;
    a test whose dry run must see the library as it is holds it shared (the
    ``library_unchanged`` fixture of tests/conftest.py).
    """
    path = tmp_path_factory.getbasetemp().parent / "thermaxis-library.lock"
    with open(path, "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)
