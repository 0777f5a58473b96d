"""The README's and the guides' result figures, written from ``results/`` and never by hand.

A guide quotes a dataset's results only inside a marked block::

    <!-- results:begin answers twin fl_thermal -->
    ... made from results/, do not edit ...
    <!-- results:end -->

The first word after ``results:begin`` is the block's kind (:data:`KINDS`), the rest its
datasets (or benchmark). ``make docs`` (``python -m thermaxis.reports.docblocks``) rewrites
every block from the results tree; ``--check`` only says which blocks differ from it, so a
change of method cannot leave a stale figure in a guide unnoticed.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Callable
from pathlib import Path

import pandas as pd

from thermaxis.errors import DataError
from thermaxis.pipeline import paths
from thermaxis.tables import markdown_table

__all__ = ["KINDS", "blocks_of", "render", "rewrite", "main"]

BLOCK = re.compile(
    r"(?P<begin><!-- results:begin (?P<spec>[^>]*?) -->\n)(?P<body>.*?)(?P<end><!-- results:end -->)",
    flags=re.S,
)


def _need(path: Path) -> Path:
    if not path.is_file():
        raise DataError(
            f"{path}: missing; the guides' result blocks are made from it (make results)"
        )
    return path


def _answers(results: Path, names: list[str]) -> str:
    """Per dataset, the answer line `make results` ends with (thermaxis.reports.answer)."""
    from thermaxis.reports.answer import answer_sentence, read_answer

    lines = []
    for name in names:
        _need(results / name / "compensation" / "model.json")
        statement = _statement(results / name)
        lines.append(f"- `{name}` ({statement}): {answer_sentence(read_answer(results / name))}")
    return "\n".join(lines) + "\n"


def _statement(folder: Path) -> str:
    """SIMULATED or MEASURED, as the dataset's model.json says."""
    import json

    with open(folder / "compensation" / "model.json", encoding="utf-8") as fh:
        simulated = json.load(fh).get("simulated", False)
    return "SIMULATED data" if simulated else "MEASURED data"


def _held_out(results: Path, names: list[str]) -> str:
    """The held-out error of the error curves per dataset, approach and algorithm, as
    results/_datasets/summary.md gives it (thermaxis.reports.crossdataset.summarise), from
    each dataset's metrics table."""
    from thermaxis.reports.crossdataset import read_metrics, summarise

    metrics = {n: read_metrics(_need(results / n / paths.METRICS)) for n in names}
    data = {n: _statement(results / n).split()[0].lower() for n in names}
    summary = summarise(metrics, data)
    shown = summary[["dataset", "data", "approach", "algorithm", "n_folds", "mean_rmse_um",
                     "mean_max_abs_um", "worst_max_abs_um"]]  # fmt: skip
    return markdown_table(shown, "%.2f")


def _faithfulness(results: Path, names: list[str]) -> str:
    """The twin's faithfulness table, verbatim."""
    (name,) = names
    path = _need(results / name / paths.FAITHFULNESS)
    return markdown_table(pd.read_csv(path, dtype=str, keep_default_na=False), "%.3f")


def _comparison(results: Path, names: list[str]) -> pd.DataFrame:
    (name,) = names
    return pd.read_csv(_need(results / "_benchmarks" / name / "comparison.csv"))


def _benchmark_line(results: Path, names: list[str]) -> str:
    """Where thermaxis stands against a benchmark's best published model, in a sentence,
    from results/_benchmarks/<name>/comparison.csv."""
    table = _comparison(results, names)
    gaps = table["mae_um"] - table["best_published_mae_um"]
    above = "".join(
        f"; on {c} it is {g:.2f} µm above the {b}"
        for c, g, b in zip(table["channel"], gaps, table["best_published"], strict=True)
        if g >= 0
    )
    return (
        f"thermaxis's test MAE is {' / '.join(f'{v:.2f}' for v in table['mae_um'])} µm on "
        f"{', '.join(table['channel'])}, against "
        f"{' / '.join(f'{v:.2f}' for v in table['best_published_mae_um'])} µm for the best "
        f"published model: below it on {int((gaps < 0).sum())} of {len(table)} channels{above}.\n"
    )


def _benchmark(results: Path, names: list[str]) -> str:
    """A benchmark's comparison as comparison.md shows it, and the sentence."""
    from thermaxis.benchmark.__main__ import shown_table

    table = markdown_table(shown_table(_comparison(results, names)), "%.3g")
    return table + "\n" + _benchmark_line(results, names)


# kind -> the function that writes its body from results/ and the block's names
KINDS: dict[str, Callable[[Path, list[str]], str]] = {
    "answers": _answers,
    "held-out": _held_out,
    "faithfulness": _faithfulness,
    "benchmark": _benchmark,
    "benchmark-line": _benchmark_line,
}


def blocks_of(text: str) -> list[tuple[str, list[str], str]]:
    """Each block of ``text``: its kind, its names and its body."""
    out = []
    for match in BLOCK.finditer(text):
        kind, *names = match["spec"].split()
        out.append((kind, names, match["body"]))
    return out


def render(kind: str, names: list[str], results: Path, where: str) -> str:
    if kind not in KINDS:
        raise DataError(
            f"{where}: unknown results block {kind!r}; expected one of {', '.join(KINDS)}"
        )
    if not names:
        raise DataError(f"{where}: results block {kind!r} names no dataset")
    return KINDS[kind](results, names)


def rewrite(text: str, results: Path, where: str = "the guide") -> str:
    """``text`` with every block's body made again from ``results``."""
    return BLOCK.sub(
        lambda m: (
            m["begin"]
            + render(m["spec"].split()[0], m["spec"].split()[1:], results, where)
            + m["end"]
        ),
        text,
    )


def main(argv: list[str] | None = None) -> int:
    """``python -m thermaxis.reports.docblocks [--results results] [--check] FILE ...``."""
    from thermaxis.pipeline.runner import write_text

    parser = argparse.ArgumentParser(prog="python -m thermaxis.reports.docblocks",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("files", type=Path, nargs="+", help="README.md and guides to rewrite")
    parser.add_argument("--results", type=Path, default=Path("results"))
    parser.add_argument("--check", action="store_true", help="only list the stale blocks")
    args = parser.parse_args(argv)
    try:
        # Every file made first, then written: nothing half-rewritten on an error.
        texts = {path: path.read_text(encoding="utf-8") for path in args.files}
        made = {path: rewrite(text, args.results, str(path)) for path, text in texts.items()}
    except DataError as exc:
        print(f"thermaxis error: {exc}", file=sys.stderr)
        return 1
    stale = [
        f"{path}: results block {kind} {' '.join(names)}"
        for path in args.files
        for (kind, names, body), (_, _, fresh) in zip(
            blocks_of(texts[path]), blocks_of(made[path]), strict=True
        )
        if body != fresh
    ]
    if args.check:
        for line in stale:
            print(f"stale: {line} differs from {args.results}", file=sys.stderr)
        return 1 if stale else 0
    for path in args.files:
        if made[path] != texts[path]:
            write_text(made[path], path)
    print(f"thermaxis: {len(stale)} result block(s) rewritten from {args.results}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
