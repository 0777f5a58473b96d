"""One fontTools subset per glyph set and process, for the PDFs :func:`save_figure` writes.

matplotlib's PDF writer subsets the embedded font anew for every PDF
(``matplotlib.backends._backend_pdf_ps.get_glyphs_subset``), and subsetting DejaVu Sans
with fontTools costs more than drawing a figure (about 0.1 s against 0.05–0.1 s). A
family's figures share a handful of glyph sets: the twin's 24 prediction figures use 6.
Within :func:`shared_font_subsets`, a glyph set's subset is made once and its bytes are
handed to every later PDF that needs the same glyphs, so each PDF is byte-identical to
one written without it (``tests/unit/test_plotting.py``).

The hook is matplotlib's private function, patched only while a figure is saved (in any
thread) and restored after. matplotlib is pinned (``envs/``); a release that renames the
function fails the byte-identity test, not a run.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Iterable, Iterator
from contextlib import contextmanager

from matplotlib.backends import _backend_pdf_ps

_MAX_GLYPH_SETS = 64  # a few KB each; a family uses a handful


class _SavedSubset:
    """A subset font as the PDF writer uses it (opened, saved once): its saved bytes."""

    def __init__(self, data: bytes):
        self._data = data

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> bool:
        return False

    def save(self, file, reorderTables: bool = True) -> None:  # noqa: N803 (fontTools' name)
        file.write(self._data)


# matplotlib's own, taken at import: the one function that makes a subset.
_make_subset = _backend_pdf_ps.get_glyphs_subset


@functools.lru_cache(maxsize=_MAX_GLYPH_SETS)
def _saved_subset(fontfile, glyphs: frozenset) -> tuple[bytes, dict]:
    with _make_subset(fontfile, glyphs) as subset:
        data = _backend_pdf_ps.font_as_file(subset.font).getvalue()
        return data, dict(subset.glyph_index_map)


def _get_glyphs_subset(fontfile, glyphs: Iterable[int]):
    data, index_map = _saved_subset(fontfile, frozenset(glyphs))
    return _backend_pdf_ps.SubsetResults(_SavedSubset(data), dict(index_map))._as_cm()


# Saves in several threads share one hook: the first to enter installs it, the last to
# leave puts back what was there.
_lock = threading.Lock()
_active = 0
_replaced = _make_subset


@contextmanager
def shared_font_subsets() -> Iterator[None]:
    """Within the block, PDFs with the same glyphs of a font embed one subset's bytes."""
    global _active, _replaced
    with _lock:
        if _active == 0:
            _replaced = _backend_pdf_ps.get_glyphs_subset
            _backend_pdf_ps.get_glyphs_subset = _get_glyphs_subset
        _active += 1
    try:
        yield
    finally:
        with _lock:
            _active -= 1
            if _active == 0:
                _backend_pdf_ps.get_glyphs_subset = _replaced
