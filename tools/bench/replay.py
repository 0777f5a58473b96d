"""Replay choice rules on the recommendation's fold scores of every record at hand.

``python -m tools.bench.replay RESULTS [--doc docs/recommendation.md]`` reads each
``RESULTS/<record>/recommend/folds/*.csv`` (what the ``recommend`` job wrote: every
candidate's inner and outer scores), makes each rule's choice per outer fold from the
inner scores alone, and gives the mean held-out RMSE of the choices beside the two
plain references and the paper's configuration on the same folds. With ``--doc`` the
table replaces the block between the replay markers of that file, so the document's
figures come from the score files, never typed by hand.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd

from thermaxis.labels import natural_sorted
from thermaxis.method.candidates import BASELINE, EVIDENCE
from thermaxis.method.nested import COMBINED
from thermaxis.pipeline import paths
from thermaxis.statistics.paired import wilcoxon_p
from thermaxis.tables import read_table
from tools.bench.records import RECORD_TARGETS, meets_targets

__all__ = ["RULES", "replay", "replay_markdown", "previous_rule", "lowest_mean"]

START, END = "<!-- replay:start -->", "<!-- replay:end -->"


def previous_rule(inner: pd.DataFrame, order: Sequence[str]) -> str:
    """The rule replaced on 2026-12-07: the ridge with lags stands unless another candidate's
    paired inner differences have mean + one standard error below zero and a one-sided
    signed-rank p at most 0.05; among those the lowest mean (largest |residual|)."""
    wide = inner.pivot_table(index="held_out", columns="candidate", values="max_abs")
    differences = wide.drop(columns=BASELINE).sub(wide[BASELINE], axis=0)
    n = len(differences)
    if n < 2:
        return BASELINE
    error = differences.std(ddof=1) / np.sqrt(n)
    beaten = [
        c
        for c in differences.columns
        if differences[c].mean() + error[c] < 0
        and wilcoxon_p(differences[c], alternative="less") <= 0.05
    ]
    means = wide.mean()
    return min(beaten, key=lambda c: (means[c], list(order).index(c))) if beaten else BASELINE


def lowest_mean(inner: pd.DataFrame, order: Sequence[str], score: str) -> str:
    """The cross-validation selector replaced on 2026-12-07 by the super learner: the
    candidate with the lowest mean inner ``score``; ties (1e-12 relative) to the first listed."""
    means = inner.pivot_table(index="held_out", columns="candidate", values=score).mean()
    best = min(means.loc[list(order)])
    return next(n for n in order if np.isclose(means[n], best, rtol=1e-12, atol=0.0))


def _per_fold(choose: Callable[[pd.DataFrame, Sequence[str]], str]):
    """A rule choosing per outer fold from that fold's inner scores (the paper's without any)."""

    def rule(scores: pd.DataFrame, order: Sequence[str]) -> pd.Series:
        inner = scores.loc[scores["kind"] == "inner"]
        folds = natural_sorted(pd.unique(scores["fold"]).tolist())
        return pd.Series(
            {
                f: choose(inner.loc[inner["fold"] == f], order)
                if (inner["fold"] == f).any()
                else "paper"
                for f in folds
            }
        )

    return rule


def _deployed(scores: pd.DataFrame, order: Sequence[str]) -> pd.Series:
    """The super learner, as the recommend job weighted it fold by fold."""
    folds = natural_sorted(pd.unique(scores["fold"]).tolist())
    return pd.Series(dict.fromkeys(folds, COMBINED))


RULES = {
    "**super learner of `recommend.combine`** (deployed)": _deployed,
    "lowest mean inner RMSE (replaced)": _per_fold(partial(lowest_mean, score="rmse")),
    "lowest mean inner largest \\|residual\\|": _per_fold(partial(lowest_mean, score="max_abs")),
    "ridge with lags unless 1 SE + signed-rank (previous)": _per_fold(previous_rule),
}


def replay(scores: pd.DataFrame) -> dict[str, float]:
    """Mean held-out RMSE (µm) of each rule's choices and of the references, on one record."""
    order = [c for c in dict.fromkeys(scores["candidate"]) if c != COMBINED]
    outer = scores.loc[scores["kind"] == "loco"].set_index(["candidate", "held_out"])["rmse"]
    out = {}
    for name, rule in RULES.items():
        chosen = rule(scores, order)
        out[name] = float(np.mean([outer[(c, fold)] for fold, c in chosen.items()]))
    folds = chosen.index
    for name in ("paper", BASELINE, EVIDENCE):
        out[name] = float(np.mean([outer[(name, fold)] for fold in folds]))
    return out


def record_scores(results: Path) -> dict[str, pd.DataFrame]:
    """Each record's fold scores under ``results``, in natural order of the record names."""
    records = {}
    fold_scores = Path(paths.FOLD_SCORES).parent
    for folder in natural_sorted([p.name for p in results.iterdir() if (p / fold_scores).is_dir()]):
        files = sorted((results / folder / fold_scores).glob("*.csv"))
        if files:
            records[folder] = pd.concat([read_table(f) for f in files], ignore_index=True)
    return records


def replay_markdown(records: dict[str, pd.DataFrame]) -> str:
    """One row per rule (and reference), one column per record: RMSE (÷ the better reference)."""
    figures = {name: replay(scores) for name, scores in records.items()}
    names = list(figures)
    lines = [
        "| rule or reference | " + " | ".join(names) + " |",
        "|---|" + "---:|" * len(names),
    ]
    rows = [*RULES, BASELINE, EVIDENCE, "paper"]
    labels = {BASELINE: f"`{BASELINE}` always", EVIDENCE: f"`{EVIDENCE}` always",
              "paper": "the paper's configuration always"}  # fmt: skip
    for row in rows:
        cells = []
        for name in names:
            f = figures[name]
            better = min(f[BASELINE], f[EVIDENCE])
            cells.append(f"{f[row]:.2f} ({f[row] / better:.2f})")
        lines.append(f"| {labels.get(row, row)} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n\n" + _bounds_sentence(figures) + "\n"


def _bounds_sentence(figures: dict[str, dict[str, float]]) -> str:
    """Where the deployed rule meets issue 61's bounds (tools.bench.records.RECORD_TARGETS)."""
    deployed = next(iter(RULES))
    missed = []
    for name, f in figures.items():
        vs_better = f[deployed] / min(f[BASELINE], f[EVIDENCE])
        vs_paper = f[deployed] / f["paper"]
        if not meets_targets(vs_better, vs_paper):
            missed.append(f"{name} ({vs_better:.2f} x the better reference, "
                          f"{vs_paper:.2f} x the paper's)")  # fmt: skip
    met = len(figures) - len(missed)
    sentence = (
        f"The deployed rule meets both bounds (at most {RECORD_TARGETS['references']:.2f} x the "
        f"better plain reference and {RECORD_TARGETS['paper']:.2f} x the paper's configuration) "
        f"on {met} of {len(figures)} records"
    )
    return sentence + (f"; it misses them on {', '.join(missed)}." if missed else ".")


def with_table(document: str, table: str, start: str = START, end: str = END) -> str:
    """``document`` with the block between the markers ``start`` and ``end`` replaced by ``table``."""
    if start not in document or end not in document:
        raise ValueError(f"the document has no {start} ... {end} block")
    head, rest = document.split(start, 1)
    _, tail = rest.split(end, 1)
    return f"{head}{start}\n{table}{end}{tail}"


def table_command(argv, prog: str, doc: str, table_of, blocks: dict[str, tuple[str, str]]) -> int:
    """A command printing ``table_of(results folder)`` and, with ``--doc``, writing it between
    the markers of that document's block ``blocks[--block]`` (default: the first); a
    ValueError or an unknown block is one line, status 2."""
    parser = argparse.ArgumentParser(prog, description=doc)
    parser.add_argument("results", type=Path, help="a bench results folder of records")
    parser.add_argument("--doc", type=Path, help="the document to write the table into")
    parser.add_argument(
        "--block", default=next(iter(blocks)), help=f"the block of --doc: {', '.join(blocks)}"
    )
    args = parser.parse_args(argv)
    if args.block not in blocks:
        print(f"thermaxis error: --block {args.block!r}: expected one of {', '.join(blocks)}",
              file=sys.stderr)  # fmt: skip
        return 2
    try:
        table = table_of(args.results)
    except ValueError as exc:
        print(f"thermaxis error: {exc}", file=sys.stderr)
        return 2
    if args.doc:
        text = args.doc.read_text(encoding="utf-8")
        args.doc.write_text(with_table(text, table, *blocks[args.block]), encoding="utf-8")
    print(table, end="")
    return 0


def _replay_table(results: Path) -> str:
    records = record_scores(results)
    if not records:
        raise ValueError(f"{results}: no <record>/recommend/folds/*.csv")
    return replay_markdown(records)


def main(argv=None) -> int:
    return table_command(
        argv, "python -m tools.bench.replay", __doc__, _replay_table, {"replay": (START, END)}
    )


if __name__ == "__main__":
    sys.exit(main())
