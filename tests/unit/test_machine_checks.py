"""The results folder's write check before any job, and a full disk named in one line.

Read-only folders are made with a read-only bind mount or the immutable flag, since root
ignores permission bits; tests skip, saying why, where neither is permitted.
"""

from __future__ import annotations

import subprocess

import pandas as pd
import pytest

from thermaxis.errors import DataError
from thermaxis.pipeline.preflight import check_writable
from thermaxis.pipeline.runner import fault_line, machine_fault, write_csv


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(list(args), capture_output=True, text=True)


def _skip_on_failure(proc: subprocess.CompletedProcess, what: str) -> None:
    if proc.returncode != 0:
        pytest.skip(f"{what} not permitted here: {(proc.stderr or proc.stdout).strip()}")


def test_a_writable_folder_and_a_missing_one_below_it_pass(tmp_path):
    check_writable(tmp_path)
    check_writable(tmp_path / "results" / "tiny")


@pytest.mark.mount
def test_a_read_only_mount_is_named_with_the_folder_that_exists(tmp_path):
    results = tmp_path / "results"
    results.mkdir()
    _skip_on_failure(_run("mount", "--bind", str(results), str(results)), "a bind mount")
    try:
        _skip_on_failure(
            _run("mount", "-o", "remount,ro,bind", str(results)), "a read-only bind mount"
        )
        with pytest.raises(DataError) as exc:
            check_writable(results / "tiny")
        assert str(exc.value).startswith(f"{results / 'tiny'} (its folder {results}): ")
        assert "read-only file system" in str(exc.value) and "\n" not in str(exc.value)
    finally:
        _run("umount", "-l", str(results))


def test_an_immutable_folder_cannot_be_written_even_by_root(tmp_path):
    results = tmp_path / "results"
    results.mkdir()
    _skip_on_failure(_run("chattr", "+i", str(results)), "chattr +i")
    try:
        with pytest.raises(DataError, match="cannot be written"):
            check_writable(results)
    finally:
        _run("chattr", "-i", str(results))


@pytest.mark.mount
def test_a_full_disk_names_the_file_and_leaves_nothing(tmp_path):
    disk = tmp_path / "disk"
    disk.mkdir()
    _skip_on_failure(_run("mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(disk)), "tmpfs")
    try:
        table = pd.DataFrame({"x": range(100_000)})
        with pytest.raises(OSError) as exc:
            write_csv(table, disk / "big.csv")
        assert machine_fault(exc.value)
        assert fault_line(exc.value).startswith(f"{disk / 'big.csv'}: no space left on the device")
        assert list(disk.iterdir()) == []
    finally:
        _run("umount", "-l", str(disk))
