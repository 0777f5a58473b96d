"""One timed command: wall and CPU time, peak RSS of the process and of its tree."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

MIB = 1024.0 * 1024.0
# Linux reports ru_maxrss in KiB, macOS in bytes.
_MAXRSS_UNIT = 1.0 if sys.platform == "darwin" else 1024.0


@dataclass
class Measurement:
    """One timed command."""

    name: str
    description: str
    command: list[str]
    wall_s: float
    cpu_s: float
    peak_rss_mib: float
    peak_tree_rss_mib: float | None
    returncode: int
    log: str
    runs: int | None = None
    extra: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.returncode == 0


class _TreeSampler(threading.Thread):
    """Largest summed RSS of a process and its descendants, sampled."""

    def __init__(self, pid: int, every_s: float = 0.2):
        super().__init__(daemon=True)
        self.pid, self.every_s = pid, every_s
        self.peak_bytes = 0
        self.available = True
        self._stop_event = threading.Event()

    def run(self) -> None:
        try:
            import psutil
        except ImportError:
            self.available = False
            return
        try:
            root = psutil.Process(self.pid)
        except psutil.Error:
            return
        while not self._stop_event.is_set():
            total = 0
            try:
                for proc in [root, *root.children(recursive=True)]:
                    try:
                        total += proc.memory_info().rss
                    except psutil.Error:
                        pass
            except psutil.Error:
                break
            self.peak_bytes = max(self.peak_bytes, total)
            self._stop_event.wait(self.every_s)

    def stop(self) -> None:
        self._stop_event.set()
        self.join(timeout=5)


def measure(
    name: str,
    command: list[str],
    cwd: Path,
    log_path: Path,
    description: str = "",
    env: dict | None = None,
    timeout_s: float | None = None,
    runs: int | None = None,
) -> Measurement:
    """Run ``command`` in ``cwd`` and measure it; stdout and stderr go to ``log_path``.

    Parameters
    ----------
    name, description : str
        Identify the measurement in bench.json.
    command : list of str
    cwd : Path
    log_path : Path
        Created (with its folder); overwritten.
    env : dict, optional
        Environment of the command (default: this process's).
    timeout_s : float, optional
        The process group is terminated after this long; the measurement keeps the
        time until then and a non-zero return code.
    runs : int, optional
        Number of runs of the dataset (scale series).

    Returns
    -------
    Measurement
        Wall time, CPU time (user + system of the whole process tree), the largest
        single process's peak RSS and, with psutil, the sampled peak RSS of the tree.
    """
    log_path.parent.mkdir(parents=True, exist_ok=True)
    with open(log_path, "wb") as log:
        start = time.perf_counter()
        proc = subprocess.Popen(
            command, cwd=cwd, env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True
        )
        sampler = _TreeSampler(proc.pid)
        sampler.start()
        timer = None
        if timeout_s:
            timer = threading.Timer(timeout_s, _terminate_group, args=(proc.pid,))
            timer.start()
        # wait4, not Popen.wait: its rusage covers the child and every descendant it reaped.
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        if timer is not None:
            timer.cancel()
        sampler.stop()
    proc.returncode = os.waitstatus_to_exitcode(status)
    return Measurement(
        name=name,
        description=description,
        command=[str(c) for c in command],
        wall_s=round(wall, 3),
        cpu_s=round(usage.ru_utime + usage.ru_stime, 3),
        peak_rss_mib=round(usage.ru_maxrss * _MAXRSS_UNIT / MIB, 1),
        peak_tree_rss_mib=round(sampler.peak_bytes / MIB, 1) if sampler.available else None,
        returncode=proc.returncode,
        log=str(log_path),
        runs=runs,
    )


def _terminate_group(pid: int) -> None:
    try:
        os.killpg(pid, signal.SIGTERM)
    except ProcessLookupError:
        pass


def _add_jobs(m: Measurement) -> None:
    if Path(m.command[0]).name == "snakemake" and "jobs" not in m.extra:
        m.extra["jobs"] = _count_jobs(Path(m.log))


def _count_jobs(log: Path) -> int | None:
    """Jobs Snakemake ran, from its 'N of M steps' lines."""
    if not log.is_file():
        return None
    lines = log.read_text(errors="replace").splitlines()
    done = [line for line in lines if "steps (" in line and " of " in line]
    if not done:
        # A dry run plans jobs and runs none: its job stats end with "total <n>".
        planned = [
            line.split()[1]
            for line in lines
            if line.startswith("total ") and line.split()[1:2] != []
        ]
        return int(planned[-1]) if planned and planned[-1].isdigit() else 0
    try:
        return int(done[-1].split(" of ")[1].split()[0])
    except (IndexError, ValueError):
        return None
