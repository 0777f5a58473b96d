"""``python -m thermaxis.benchmark SPEC.yaml --out FOLDER``: a published protocol, reproduced.

Reads the record through the spec's import mapping (the importer's own reader and
checks), runs :mod:`thermaxis.benchmark.chronological` on every displacement channel and
writes ``comparison.csv`` and ``comparison.md`` into ``FOLDER``: thermaxis's test
error per channel beside the published figures.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

from thermaxis.benchmark.chronological import block, evaluate_channel, input_sets
from thermaxis.dataset.import_mapping import load_mapping, table_layout
from thermaxis.dataset.import_parsing import read_numeric, read_seconds, read_wide_table
from thermaxis.dataset.safety import load_yaml
from thermaxis.errors import DataError
from thermaxis.pipeline.runner import thread_pools, write_csv, write_text
from thermaxis.tables import markdown_table


def read_record(spec: dict, spec_path: Path):
    """Seconds, temperatures, operating signals and the displacement channels of the record."""
    mapping_path = (spec_path.parent / spec["mapping"]).resolve()
    mapping = load_mapping(mapping_path)
    source = (mapping_path.parent / mapping["source"]).resolve()
    frame = read_wide_table(source, *table_layout(mapping))
    seconds = read_seconds(source, frame, mapping["time"])
    temperatures = {
        s["id"]: read_numeric(source, frame, s["column"], False) for s in mapping["sensors"]
    }
    signals = {s["id"]: read_numeric(source, frame, s["column"], False) for s in mapping["signals"]}
    channels = {c: read_numeric(source, frame, c, False) for c in spec["channels"]}
    return seconds, temperatures, signals, channels


def comparison(spec: dict, spec_path: Path) -> pd.DataFrame:
    seconds, temperatures, signals, channels = read_record(spec, spec_path)
    n = len(seconds)
    train, test = block(n, spec["protocol"]["train"]), block(n, spec["protocol"]["test"])
    c = spec["candidates"]
    sets = input_sets(
        seconds, temperatures, signals, c["inputs"], c["lag_sets_min"], c.get("rate_sets_min", [[]])
    )
    rows = []
    for j, (channel, y) in enumerate(channels.items()):
        result = evaluate_channel(
            sets, y, train, test, c["ridge_alpha"], int(c["validation_splits"])
        )
        published = {m["name"]: float(m["values"][j]) for m in spec["published"]["models"]}
        best_name = min(published, key=published.get)
        rows.append(
            {
                "channel": channel,
                **result,
                "best_published": best_name,
                "best_published_mae_um": published[best_name],
                "below_best_published": bool(result["mae_um"] < published[best_name]),
                **{f"published_mae_um: {name}": value for name, value in published.items()},
                "n_train": train.stop - train.start,
                "n_test": test.stop - test.start,
            }
        )
    return pd.DataFrame(rows)


def shown_table(table: pd.DataFrame) -> pd.DataFrame:
    """The comparison as comparison.md and the guides show it: thermaxis's MAE, each
    published model's, and the chosen inputs."""
    shown = table[["channel", "mae_um", *[c for c in table.columns if c.startswith("published_mae_um: ")],
                   "inputs", "ridge_alpha"]]  # fmt: skip
    return shown.rename(
        columns=lambda c: c.replace("published_mae_um: ", "published: ").replace(
            "mae_um", "thermaxis MAE (um)"
        )
    )


def markdown(table: pd.DataFrame, spec: dict) -> str:
    shown = shown_table(table)
    wins = int(table["below_best_published"].sum())
    head = (
        f"# {spec['name']}: the authors' protocol (train {spec['protocol']['train']}, test {spec['protocol']['test']} "
        "of the record)\n\n"
        f"MEASURED data. {spec['citation'].strip()}\n\n"
        f"thermaxis's test MAE is below the best published model's on {wins} of {len(table)} channels; every "
        "choice was made inside the training part (scikit-learn TimeSeriesSplit).\n\n"
    )
    return head + markdown_table(shown, "%.3g")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m thermaxis.benchmark", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "spec", type=Path, help="benchmark spec (e.g. data/benchmarks/fl_thermal.yaml)"
    )
    parser.add_argument(
        "--out",
        type=Path,
        required=True,
        help="output folder (e.g. results/_benchmarks/fl_thermal)",
    )
    args = parser.parse_args(argv)
    try:
        spec = load_yaml(args.spec)
        # One BLAS thread, as a one-core job has: the ridge paths are small systems, and a
        # second thread spinning beside them doubled the CPU time (11.1 against 5.4 s alone,
        # 19 against 5.6 s beside another process on two cores; docs/performance.md).
        with thread_pools(1):
            table = comparison(spec, args.spec)
    except DataError as exc:
        print(f"thermaxis error: {exc}", file=sys.stderr)
        return 1
    args.out.mkdir(parents=True, exist_ok=True)
    write_csv(table, args.out / "comparison.csv", float_format="%.6g")
    write_text(markdown(table, spec), args.out / "comparison.md")
    below = int(table["below_best_published"].sum())
    print(
        f"thermaxis: benchmark {spec['name']}: {len(table)} channel(s), {below} below the best "
        f"published MAE -> {args.out / 'comparison.csv'}",
        file=sys.stderr,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
