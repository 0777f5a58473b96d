"""Resource requests of the workflow's rules, from the benchmarks a run recorded.

Every rule writes a Snakemake benchmark (``benchmarks/<dataset>/...tsv``: wall seconds
``s``, peak resident memory ``max_rss`` in MB, ...).  A scheduler such as Slurm needs
a memory and time limit per job before it runs; this module turns the measured
peaks into requests with headroom, so that the values in the rules' ``resources:``
blocks are reproducible::

    python -m thermaxis.pipeline.resources benchmarks/twin

prints one line per rule: its benchmarks, the measured peaks and the requests.
Which benchmark files belong to which rule is read from the rule files
(``benchmark:`` paths), so a new rule needs no entry here.

Every rule declares its requests through :func:`per_attempt` (``thermaxis.pipeline.tuning``
keeps the per-rule values, beside the floors :data:`MIN_MEMORY_MB` and
:data:`MIN_RUNTIME_MIN` every rule gets at least).
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from thermaxis.errors import DataError

__all__ = [
    "Request",
    "benchmark_globs",
    "request",
    "requests_from_benchmarks",
    "per_attempt",
    "main",
]

# Headroom: memory grows with the data and differs between nodes; a time limit hit
# kills a job, so it is generous and never below a few minutes of queue-side slack.
MEMORY_FACTOR = 2.0
MEMORY_STEP_MB = 250
MIN_MEMORY_MB = 500
RUNTIME_FACTOR = 5.0
MIN_RUNTIME_MIN = 5

_RULE = re.compile(r"^rule (\w+):", re.MULTILINE)
_BENCHMARK = re.compile(r"^\s+benchmark:\s*\n\s+f?\"\{BENCH\}/([^\"]+)\"", re.MULTILINE)


@dataclass(frozen=True)
class Request:
    """One rule's measured peaks and the requests derived from them."""

    rule: str
    n_benchmarks: int
    max_s: float
    max_rss_mb: float
    mem_mb: int
    runtime_min: int


def benchmark_globs(rule_sources: Iterable[str]) -> dict[str, str]:
    """{rule: glob of its benchmark files relative to benchmarks/<dataset>/}.

    Wildcards (``{{run}}``) and workflow constants (``{SWEEP_BATCHES}``) become ``*``.
    """
    globs = {}
    for text in rule_sources:
        starts = [(m.start(), m.group(1)) for m in _RULE.finditer(text)] + [(len(text), None)]
        for (start, rule), (end, _) in zip(starts, starts[1:], strict=False):
            found = _BENCHMARK.search(text, start, end)
            if found:
                globs[rule] = re.sub(r"\{+[^{}]*\}+", "*", found.group(1))
    return globs


def request(max_s: float, max_rss_mb: float) -> tuple[int, int]:
    """(mem_mb, runtime in minutes) for a job that took ``max_s`` s and ``max_rss_mb`` MB at most."""
    mem = max(
        MIN_MEMORY_MB, math.ceil(MEMORY_FACTOR * max_rss_mb / MEMORY_STEP_MB) * MEMORY_STEP_MB
    )
    runtime = max(MIN_RUNTIME_MIN, math.ceil(RUNTIME_FACTOR * max_s / 60.0))
    return int(mem), int(runtime)


def per_attempt(mem_mb: int, runtime_min) -> dict:
    """Snakemake ``resources`` of a rule: memory (MB) and runtime (minutes) of its first attempt.

    A retry (``--retries``) asks for the attempt number times both. ``runtime_min`` may be
    a function of the job's wildcards (the sweep's batches: their share of the grid).
    """
    minutes = runtime_min if callable(runtime_min) else (lambda wildcards: runtime_min)
    return {
        "mem_mb": lambda wildcards, attempt: mem_mb * attempt,
        "runtime": lambda wildcards, attempt: minutes(wildcards) * attempt,
    }


def _read(path: Path) -> pd.DataFrame:
    frame = pd.read_csv(path, sep="\t")
    for column in ("s", "max_rss"):
        if column not in frame.columns:
            raise DataError(
                f"{path}: column {column!r} missing; expected a Snakemake benchmark table"
            )
    # Snakemake writes "-" where it could not measure (a job too short to sample).
    return frame[["s", "max_rss"]].apply(pd.to_numeric, errors="coerce")


def requests_from_benchmarks(bench_dir, globs: Mapping[str, str]) -> list[Request]:
    """A :class:`Request` per rule that has at least one benchmark under ``bench_dir``.

    A file that one rule names exactly (``compensation/model.tsv``) is not also another
    rule's (``compensation/*.tsv``).
    """
    bench_dir = Path(bench_dir)
    named = {bench_dir / pattern for pattern in globs.values() if "*" not in pattern}
    out = []
    for rule in sorted(globs):
        files = sorted(bench_dir.glob(globs[rule]))
        if "*" in globs[rule]:
            files = [f for f in files if f not in named]
        if not files:
            continue
        frame = pd.concat([_read(p) for p in files], ignore_index=True)
        max_s, max_rss = float(frame["s"].max()), float(frame["max_rss"].fillna(0).max())
        mem, runtime = request(max_s, max_rss)
        out.append(Request(rule, len(files), max_s, max_rss, mem, runtime))
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m thermaxis.pipeline.resources", description=__doc__.splitlines()[0]
    )
    parser.add_argument("bench_dir", help="benchmarks/<dataset> of a finished run")
    parser.add_argument(
        "--rules",
        default="workflow/rules",
        help="folder of the rule files (default workflow/rules)",
    )
    args = parser.parse_args(argv)
    globs = benchmark_globs(
        p.read_text(encoding="utf-8") for p in sorted(Path(args.rules).glob("*.smk"))
    )
    try:
        rows = requests_from_benchmarks(args.bench_dir, globs)
    except DataError as exc:
        print(f"thermaxis error: {exc}", file=sys.stderr)
        return 1
    if not rows:
        print(
            f"thermaxis error: {args.bench_dir}: no benchmark of any rule; expected a finished workflow run",
            file=sys.stderr,
        )
        return 1
    print("rule\tbenchmarks\tmax_s\tmax_rss_mb\tmem_mb\truntime_min")
    for r in rows:
        print(
            f"{r.rule}\t{r.n_benchmarks}\t{r.max_s:.2f}\t{r.max_rss_mb:.1f}\t{r.mem_mb}\t{r.runtime_min}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
