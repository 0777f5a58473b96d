"""Progress of long steps: a bar redrawn in place on a terminal, plain lines elsewhere.

A log file or a CI job gets one line per step (never carriage returns); a person at a
terminal gets one line that fills up.
"""

from __future__ import annotations

import sys
from typing import TextIO

__all__ = ["ProgressBar"]

BAR_WIDTH = 30


class ProgressBar:
    """``bar(done, total, what)``: the callable the library's ``progress`` parameters take."""

    def __init__(self, stream: TextIO | None = None, tty: bool | None = None):
        self.stream = sys.stderr if stream is None else stream
        self.tty = self.stream.isatty() if tty is None else tty
        self._open = False

    def __call__(self, done: int, total: int, what: str) -> None:
        if not self.tty:
            self.stream.write(f"[{done}/{total}] {what}\n")
            self.stream.flush()
            return
        filled = BAR_WIDTH * done // max(total, 1)
        self.stream.write(
            f"\r[{'#' * filled}{'.' * (BAR_WIDTH - filled)}] {done}/{total} {what}\033[K"
        )
        self._open = done < total
        if not self._open:
            self.stream.write("\n")
        self.stream.flush()

    def close(self) -> None:
        """End a bar left unfinished (an error mid-way), so the next line starts clean."""
        if self._open:
            self.stream.write("\n")
            self._open = False
