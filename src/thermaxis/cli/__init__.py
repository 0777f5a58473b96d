"""The ``thermaxis`` command: run, check, import, compensate, sweep and report.

Every subcommand calls the functions the workflow itself uses: ``run``, ``sweep`` and
``report`` start Snakemake through the recovery wrapper of ``make results``
(:mod:`thermaxis.pipeline.resume`), ``check`` is the workflow's parse-time gate
(:func:`thermaxis.pipeline.preflight.check_before_jobs`), ``import`` the importer and
``compensate`` the controller runtime (:class:`thermaxis.compensation.runtime.Compensator`).
A bad input ends in one line, ``thermaxis error: <message>``, and exit status 1.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

from thermaxis.errors import DataError

__all__ = ["build_parser", "main"]

SNAKEMAKE_COMMANDS = ("run", "sweep", "report")
CHECKOUT_NEEDED = (
    "run it in a thermaxis checkout (the folder with the Snakefile): the workflow is not part of "
    "the installed package"
)


def _examples(*lines: str) -> str:
    return "examples:\n" + "\n".join(f"  {line}" for line in lines)


def _subcommand(sub, name: str, summary: str, examples: tuple[str, ...], handler):
    parser = sub.add_parser(
        name,
        help=summary,
        description=summary,
        epilog=_examples(*examples),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.set_defaults(handler=handler)
    return parser


def _cores(text: str) -> str:
    """``all`` or a whole number of cores from 1: Snakemake runs with 0, and every job fails."""
    if text == "all" or (text.isdigit() and int(text) >= 1):
        return text
    raise argparse.ArgumentTypeError(
        f"expected 'all' or a whole number of cores from 1, got {text!r}"
    )


def _snakemake_parser(parser) -> None:
    parser.add_argument(
        "--cores", type=_cores, default="all", help="cores Snakemake may use (default: all)"
    )
    parser.add_argument(
        "--verbose",
        action="store_true",
        help="Snakemake's full output: every rule, reason and shell command (default: "
        "a progress bar and the rules' warnings, as make results prints; make V=1)",
    )
    parser.epilog += "\n\nArguments after -- go to Snakemake as they are."


def build_parser() -> argparse.ArgumentParser:
    # One helper per subcommand: each reads as the `--help` it gives.
    parser = argparse.ArgumentParser(
        prog="thermaxis",
        description="Thermal positioning error of machine-tool linear axes: the workflow, "
        "its checks, the importer and the compensation runtime.",
        epilog=_examples(
            "thermaxis check data/raw/twin",
            "thermaxis run",
            "thermaxis import data/import/fl_thermal.yaml --out data/raw/fl_thermal",
            "thermaxis compensate results/twin/compensation/model.json log.csv --out applied.csv",
        )
        + "\n\nEach subcommand has --help. Guide: docs/cli.md.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    _run_parser(sub)
    _check_parser(sub)
    _import_parser(sub)
    _compensate_parser(sub)
    _sweep_parser(sub)
    _report_parser(sub)
    return parser


def _run_parser(sub) -> None:
    """The `thermaxis run` subcommand and its arguments."""
    run = _subcommand(
        sub,
        "run",
        "Build the results of each dataset (what `make results` does), resuming an interrupted run.",
        (
            "thermaxis run                      # every dataset of config `datasets`",
            "thermaxis run data/raw/twin --cores 2",
            "thermaxis run data/raw/mine --verbose -- --dry-run",
        ),
        _run,
    )
    run.add_argument(
        "datasets",
        nargs="*",
        metavar="DATASET",
        help="dataset folders (default: config `datasets`)",
    )
    _snakemake_parser(run)


def _check_parser(sub) -> None:
    """The `thermaxis check` subcommand and its arguments."""
    check = _subcommand(
        sub,
        "check",
        "Every check the workflow makes before any job, in seconds, then what the dataset holds.",
        ("thermaxis check data/raw/twin", "thermaxis check data/raw/mine --configfile my.yaml"),
        _check,
    )
    check.add_argument("dataset", metavar="DATASET", help="the dataset folder")
    check.add_argument(
        "--configfile",
        action="append",
        default=[],
        help="config file(s), later ones win (default: config/config.yaml if present, else the schema's defaults)",
    )


def _import_parser(sub) -> None:
    """The `thermaxis import` subcommand and its arguments."""
    imp = _subcommand(
        sub,
        "import",
        "Turn a logger export (CSV or XLSX) into datasets of the raw layout, from an import mapping.",
        (
            "thermaxis import data/import/fl_thermal.yaml --out data/raw/fl_thermal",
            "thermaxis import mine.yaml --out data/raw/mine   # errors.channels: one dataset per channel",
        ),
        _import,
    )
    imp.add_argument(
        "mapping", metavar="MAPPING", help="the import mapping (YAML; docs/your-data.md)"
    )
    imp.add_argument(
        "--out",
        required=True,
        metavar="FOLDER",
        help="the dataset folder to write (replaced when complete)",
    )


def _compensate_parser(sub) -> None:
    """The `thermaxis compensate` subcommand and its arguments."""
    comp = _subcommand(
        sub,
        "compensate",
        "Replay a compensation over a logged temperature file cycle by cycle, with the fallback policy.",
        (
            "thermaxis compensate results/twin/compensation/model.json day.csv --out applied.csv",
            "# day.csv: a column time (ISO 8601) or time_s (seconds), one column per sensor of the model",
        ),
        _compensate,
    )
    comp.add_argument(
        "model", metavar="MODEL.json", help="a model.json of the workflow (compensation/)"
    )
    comp.add_argument(
        "log", metavar="LOG.csv", help="logged temperatures, one row per controller cycle"
    )
    comp.add_argument(
        "--out",
        required=True,
        metavar="FILE.csv",
        help="K0, tan(beta), P0 and fallback reasons per cycle",
    )
    comp.add_argument(
        "--figure", metavar="FILE.png", help="the figure (default: FILE.csv with .png)"
    )


def _sweep_parser(sub) -> None:
    """The `thermaxis sweep` subcommand and its arguments."""
    sweep = _subcommand(
        sub,
        "sweep",
        "Sweep the method's choices on one dataset (what `make sweep` does), batches as a progress bar.",
        ("thermaxis sweep", "thermaxis sweep data/raw/twin --cores 2"),
        _sweep,
    )
    sweep.add_argument(
        "dataset",
        nargs="?",
        metavar="DATASET",
        help="dataset folder (default: the first of config `datasets`)",
    )
    _snakemake_parser(sweep)


def _report_parser(sub) -> None:
    """The `thermaxis report` subcommand and its arguments."""
    report = _subcommand(
        sub,
        "report",
        "Build each dataset's pages (index.html and the reports), or Snakemake's report as a zip.",
        ("thermaxis report", "thermaxis report data/raw/fl_thermal", "thermaxis report --zip"),
        _report,
    )
    report.add_argument(
        "datasets",
        nargs="*",
        metavar="DATASET",
        help="dataset folders (default: config `datasets`)",
    )
    report.add_argument(
        "--zip",
        action="store_true",
        help="Snakemake's HTML report, results/<dataset>/report.zip (what `make report` does)",
    )
    _snakemake_parser(report)


# --------------------------------------------------------------------------- the workflow


def _config(configfiles=(), dataset: str | None = None) -> dict:
    from thermaxis.config import load_config, validate_config

    overrides = {"dataset": dataset} if dataset else None
    if configfiles or Path("config/config.yaml").is_file():
        return load_config(*configfiles, overrides=overrides)
    return validate_config(overrides or {})


def _in_checkout() -> None:
    if not Path("Snakefile").is_file():
        raise DataError(f"{Path.cwd()}: no Snakefile; {CHECKOUT_NEEDED}")


def _snakemake_command(args, extra: list[str]) -> list[str]:
    """Snakemake through the recovery wrapper of ``make results``, quiet unless ``--verbose``."""
    _in_checkout()
    snakemake = Path(sys.executable).with_name("snakemake")
    # "--logger=rich", not "--logger rich": the option takes one or more loggers, and would
    # take a target that follows it for a second one.
    output = "--printshellcmds" if args.verbose else "--logger=rich"
    return [
        sys.executable, "-m", "thermaxis.pipeline.resume", str(snakemake),
        "--cores", args.cores, output, *args.snakemake_args, *extra,
    ]  # fmt: skip


def _wrapped(command: list[str]) -> int:
    return subprocess.run(command, stdin=subprocess.DEVNULL).returncode


def _datasets(args) -> dict[str, Path]:
    """The datasets to run, each with the results/<name>/ folder it writes: two that share a
    name would overwrite one another's results, the second silently replacing the first."""
    _in_checkout()
    folders: dict[str, Path] = {}
    for dataset in args.datasets or _config()["datasets"]:
        out = _results_of(dataset)
        first = next((d for d, o in folders.items() if o == out), None)
        if first is not None:
            raise ValueError(
                f"{dataset}: listed twice"
                if Path(first).resolve() == Path(dataset).resolve()
                else f"{dataset}: dataset name {out.name!r} (its dataset.yaml) is {first}'s "
                f"too, and both would write {out}; give one of them another name"
            )
        folders[dataset] = out
    return folders


def _dry_run(args) -> bool:
    return any(a in ("-n", "--dry-run", "--dryrun") for a in args.snakemake_args)


def _run(args) -> int:
    """Each dataset's workflow, the page across every dataset under results/, then the answers."""
    from thermaxis.reports import answer, crossdataset

    folders = _datasets(args)
    for dataset in folders:
        print(f"== {dataset}", flush=True)
        code = _wrapped(_snakemake_command(args, ["--config", f"dataset={dataset}"]))
        if code:
            return code
    if _dry_run(args):
        return 0  # nothing was built to summarise
    code = crossdataset.main(["--results", "results"])
    if code:
        return code
    # The answers last, so the terminal ends with them.
    return answer.main([str(out) for out in folders.values()])


def _sweep(args) -> int:
    from thermaxis.config import dataset_of
    from thermaxis.pipeline import paths

    dataset = args.dataset or dataset_of(_config())
    code = _wrapped(_snakemake_command(args, ["--config", f"dataset={dataset}", "--", "sweep"]))
    if code:
        return code
    # The index links the sweep report only if it existed when the index was built.
    index = _results_of(dataset) / paths.INDEX
    if not index.is_file() or _dry_run(args):
        return 0
    return _wrapped(
        _snakemake_command(
            args, ["--forcerun", "index", "--config", f"dataset={dataset}", "--", str(index)]
        )
    )


def _results_of(dataset: str) -> Path:
    from thermaxis.dataset.reader import load_dataset

    return Path("results") / load_dataset(dataset).name


def _report(args) -> int:
    from thermaxis.pipeline import paths
    from thermaxis.reports import answer

    folders = _datasets(args)
    for dataset, out in folders.items():
        target = (
            ["--report", str(out / paths.REPORT_ZIP)]
            if args.zip
            else ["--", str(out / paths.INDEX)]
        )
        code = _wrapped(_snakemake_command(args, ["--config", f"dataset={dataset}", *target]))
        if code:
            return code
    return 0 if _dry_run(args) else answer.main([str(out) for out in folders.values()])


def _check(args) -> int:
    from thermaxis.cli.check import overview
    from thermaxis.pipeline.preflight import check_before_jobs

    started = time.perf_counter()
    checked = check_before_jobs(_config(args.configfile, args.dataset))
    # The overview reads every run's logs and measurements, whose checks may still refuse one.
    lines, warnings = overview(checked)
    print(f"thermaxis: {args.dataset}: every check before any job passed")
    print("\n".join(lines))
    for warning in warnings:
        print(f"thermaxis warning: {warning}", file=sys.stderr)
    print(f"checked in {time.perf_counter() - started:.2f} s")
    return 0


# --------------------------------------------------------------------------- data and models


def _import(args) -> int:
    from thermaxis.cli.progress import ProgressBar
    from thermaxis.dataset.importer import import_dataset, summary_lines

    bar = ProgressBar()
    try:
        report = import_dataset(args.mapping, args.out, progress=bar)
    finally:
        bar.close()
    print("\n".join(summary_lines(report)))
    for warning in report.warnings:
        print(f"thermaxis warning: {warning}", file=sys.stderr)
    return 0


def _compensate(args) -> int:
    from thermaxis.cli import compensate
    from thermaxis.compensation.runtime import Compensator
    from thermaxis.figures.style import save_figure
    from thermaxis.pipeline.runner import atomic_path, write_csv

    model = Compensator.from_json(args.model)
    seconds, samples = compensate.read_log(args.log, model.sensors)
    table = compensate.controller_table(compensate.replay(model, seconds, samples))
    out = Path(args.out)
    # Full precision: a controller (and a check against residuals.csv) reads these numbers back.
    write_csv(table, out, float_format="%.17g")
    figure = Path(args.figure) if args.figure else out.with_suffix(".png")
    with atomic_path(figure) as tmp:
        save_figure(
            compensate.replay_figure(
                table, f"{Path(args.log).name} through {Path(args.model).name}"
            ),
            tmp,
        )
    fallback = table[table["status"] != "ok"]
    cycles = f"{len(table)} cycle{'' if len(table) == 1 else 's'}"
    print(f"wrote {out} ({cycles}, {len(fallback)} on the fallback policy) and {figure}")
    sentence = model.model.get("deployment", {}).get("sentence")
    if sentence:
        print(f"the model's deployment verdict: {sentence}")
    return 0


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    # What follows "--" is Snakemake's, whatever it looks like (argparse would read -n as ours).
    cut = argv.index("--") if "--" in argv else len(argv)
    parser = build_parser()
    args = parser.parse_args(argv[:cut])
    args.snakemake_args = argv[cut + 1 :]
    if args.snakemake_args and args.command not in SNAKEMAKE_COMMANDS:
        parser.error(f"thermaxis {args.command} takes no Snakemake arguments (after --)")
    try:
        return args.handler(args)
    except ValueError as exc:  # DataError included: one line naming the file and what was expected
        print(
            f"thermaxis error: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}",
            file=sys.stderr,
        )
        return 1
