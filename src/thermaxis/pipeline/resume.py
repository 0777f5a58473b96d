"""Start Snakemake so that a run interrupted in any way completes on the next ``make results``.

``python -m thermaxis.pipeline.resume SNAKEMAKE [ARGS...]`` (the ``make results`` recipe):

* a Snakemake already running in this folder is never disturbed: one line says so and
  nothing starts;
* otherwise a lock left in ``.snakemake/locks`` can only come from a dead process
  (SIGKILL, a lost terminal, a power cut): it is cleared with ``snakemake --unlock``;
* temporary files of :func:`thermaxis.pipeline.runner.atomic_path` orphaned by a killed job
  are removed from ``results/``, so no partial output survives;
* Snakemake then runs with ``--rerun-incomplete``: outputs of jobs that never finished
  are made again instead of stopping the run with ``IncompleteFilesException``.

Live processes are found in ``/proc`` (their working folder and command line); where
``/proc`` does not exist a lock is never cleared automatically.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

__all__ = ["live_snakemakes", "stale_locks", "orphaned_temporaries", "main"]

PROC = Path("/proc")
# atomic_path's mkstemp names: ".<name>.<8 random characters><suffix>".
_TEMPORARY = re.compile(r"^\.(?P<name>.+)\.[a-z0-9_]{8}(?P<suffix>\.[^./]+)?$")


def _is_snakemake(argv: list[str]) -> bool:
    """Snakemake itself (``snakemake ...`` or ``python .../snakemake ...``), not a shell that names it."""
    words = [os.path.basename(a) for a in argv[:3]]
    if words and words[0] == "snakemake":
        return True
    python = bool(words) and words[0].startswith("python")
    return python and (words[1:2] == ["snakemake"] or words[1:3] == ["-m", "snakemake"])


def live_snakemakes(folder: Path, proc: Path = PROC) -> list[int]:
    """Process ids of Snakemake processes whose working folder is ``folder``."""
    folder = Path(os.path.realpath(folder))
    found = []
    for entry in proc.glob("[0-9]*"):
        try:
            argv = (entry / "cmdline").read_bytes().split(b"\0")
            cwd = Path(os.readlink(entry / "cwd"))
        except OSError:
            continue  # gone, or not ours to inspect
        if (
            int(entry.name) != os.getpid()
            and cwd == folder
            and _is_snakemake([a.decode(errors="replace") for a in argv if a])
        ):
            found.append(int(entry.name))
    return sorted(found)


def stale_locks(folder: Path) -> list[Path]:
    return sorted((folder / ".snakemake" / "locks").glob("*.lock"))


def orphaned_temporaries(results: Path) -> list[Path]:
    """Temporary files of atomic writes whose writer is gone (only called with no live Snakemake)."""
    if not results.is_dir():
        return []
    found = []
    for path in results.rglob(".*"):
        match = _TEMPORARY.match(path.name)
        if path.is_file() and match and match["name"].endswith(match["suffix"] or ""):
            found.append(path)
    return sorted(found)


def main(argv: list[str]) -> int:
    if not argv:
        print("usage: python -m thermaxis.pipeline.resume SNAKEMAKE [ARGS...]", file=sys.stderr)
        return 2
    folder = Path.cwd()
    if not PROC.is_dir():
        os.execv(argv[0], [argv[0], "--rerun-incomplete", *argv[1:]])
    live = live_snakemakes(folder)
    if live:
        print(
            f"thermaxis: Snakemake (pid {', '.join(map(str, live))}) is already running in {folder}; "
            "nothing started. Wait for it to finish, or stop it, then run make results again.",
            file=sys.stderr,
        )
        return 1
    if stale_locks(folder):
        print(
            f"thermaxis: clearing the lock of an interrupted run in {folder} (no Snakemake is running here)",
            file=sys.stderr,
        )
        unlocked = subprocess.run([argv[0], "--unlock", *argv[1:]], stdout=subprocess.DEVNULL)
        if unlocked.returncode != 0:
            return unlocked.returncode
    for path in orphaned_temporaries(folder / "results"):
        print(f"thermaxis: removing {path}, left by an interrupted job", file=sys.stderr)
        path.unlink()
    os.execv(argv[0], [argv[0], "--rerun-incomplete", *argv[1:]])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
