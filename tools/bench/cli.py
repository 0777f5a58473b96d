"""``python -m tools.bench``: the command line."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from tools.bench.report import render
from tools.bench.scaling import GROWTH_SHAPES, SCALE_RUNS, SCALE_SHAPES
from tools.bench.steps import DRYRUN_REPEATS, STEPS, _machine, run_bench


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tools.bench", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "--out", type=Path, default=Path("results/bench"), help="folder of bench.json and bench.md"
    )
    parser.add_argument(
        "--cores", type=int, default=None, help="cores given to Snakemake (default: all usable)"
    )
    parser.add_argument(
        "--runs", type=int, nargs="+", default=list(SCALE_RUNS), help="runs of the scale datasets"
    )
    parser.add_argument(
        "--shapes",
        nargs="+",
        choices=list(SCALE_SHAPES),
        default=list(GROWTH_SHAPES),
        help="shapes of the scale datasets (default: the growth shapes; sensors_60 on request)",
    )
    parser.add_argument(
        "--steps", nargs="+", choices=STEPS, default=list(STEPS), help="what to measure"
    )
    parser.add_argument(
        "--workdir", type=Path, default=None, help="scratch folder (default: a new temporary one)"
    )
    parser.add_argument(
        "--keep", action="store_true", help="keep the scratch work folders and scale datasets"
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=DRYRUN_REPEATS,
        help="times each start-up and dry-run timing is taken; the best is kept",
    )
    parser.add_argument(
        "--timeout-s", type=float, default=3600.0, help="stop any one measurement after this long"
    )
    parser.add_argument(
        "--render-only",
        action="store_true",
        help="rewrite bench.md from --out/bench.json, rerun nothing",
    )
    args = parser.parse_args(argv)
    if args.render_only:
        try:
            render(args.out)
        except ValueError as exc:
            print(f"thermaxis error: {exc}", file=sys.stderr)
            return 2
        print((args.out / "bench.md").read_text(encoding="utf-8"))
        return 0
    cores = args.cores or _machine()["usable_cores"] or 1
    if cores < 1 or args.repeats < 1 or any(n < 1 for n in args.runs):
        print("thermaxis error: --cores, --repeats and --runs must be positive integers",
              file=sys.stderr)  # fmt: skip
        return 2
    doc = run_bench(args.out, cores, args.runs, args.steps, args.workdir, args.keep, args.timeout_s,
                    shapes=args.shapes, repeats=args.repeats, progress=lambda line: print(line, file=sys.stderr, flush=True))  # fmt: skip
    print((args.out / "bench.md").read_text(encoding="utf-8"))
    return 0 if all(m["ok"] for m in doc["measurements"]) else 1
