"""Command line: ``python -m thermaxis.twin {generate,calibrate,conflicts,scale} ...``."""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

from . import model as mdl

DEFAULT_OUT = Path("data/raw/twin")
DEFAULT_TRUTH = Path("data/twin_truth")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m thermaxis.twin", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    gen = sub.add_parser(
        "generate", help="write the embedded dataset and its ground truth from twin_params.json"
    )
    gen.add_argument("--out", type=Path, default=DEFAULT_OUT)
    gen.add_argument("--truth", type=Path, default=DEFAULT_TRUTH)
    cal = sub.add_parser(
        "calibrate", help="refit twin_params.json to the published targets, then regenerate"
    )
    cal.add_argument("--out", type=Path, default=DEFAULT_OUT)
    cal.add_argument("--truth", type=Path, default=DEFAULT_TRUTH)
    cal.add_argument("--params", type=Path, default=mdl.PARAMS_PATH)
    cal.add_argument(
        "--resume",
        type=Path,
        help="a twin_params file a calibration wrote: go on after the last stage it records",
    )
    con = sub.add_parser(
        "conflicts",
        help="optimise each group of the paper's targets alone and in pairs (which conflict)",
    )
    con.add_argument("--out", type=Path, default=Path("docs/twin-conflicts.md"))
    sc = sub.add_parser("scale", help="write a large benchmark dataset (not committed)")
    sc.add_argument("--out", type=Path, required=True)
    sc.add_argument("--runs", type=int, default=50)
    sc.add_argument("--sensors", type=int, default=64)
    sc.add_argument("--positions", type=int, default=100)
    sc.add_argument("--hours", type=float, default=8.0)
    sc.add_argument("--rate-hz", type=float, default=1.0)
    sc.add_argument("--seed", type=int, default=0)
    sc.add_argument(
        "--measurement-min", type=float, default=30.0, help="minutes between measurements"
    )
    sc.add_argument(
        "--name", default="twin_scale", help="the dataset's name, so its results/<name>/ folder"
    )
    return parser


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()[:16]


def _recorded_stages(path: Path) -> list[dict]:
    with open(path, encoding="utf-8") as fh:
        return json.load(fh).get("fit", {}).get("stages") or []


def _resume_point(path: Path) -> tuple[mdl.TwinParams, str]:
    """The parameters of a written calibration and the last stage its record names."""
    stages = _recorded_stages(path)
    if not stages or "name" not in stages[-1]:
        raise ValueError(f"{path}: fit.stages names no stage (expected a calibration's record)")
    return mdl.load_params(path), stages[-1]["name"]


def main(argv: list[str] | None = None) -> int:
    # One function per subcommand; each returns the exit status.
    args = _parser().parse_args(argv)
    if args.command == "generate":
        from .generate import generate_dataset

        generate_dataset(args.out, args.truth)
        return 0
    if args.command == "calibrate":
        return _calibrate(args)
    if args.command == "conflicts":
        return _conflicts(args)
    return _scale(args)


def _calibrate(args) -> int:
    """Calibrate the twin's parameters, save them with the record of the stages, regenerate."""
    from .calibration import calibrate
    from .generate import generate_dataset
    from .stages import resume_index

    try:
        resume = _resume_point(args.resume) if args.resume else None
        if resume is not None:
            resume_index(resume[1])
    except (OSError, ValueError) as exc:
        print(f"error: {args.resume}: {exc}", file=sys.stderr)
        return 2
    result = calibrate(resume=resume)
    start = (
        f"resumed after stage {resume[1]!r} from {args.resume.name} (sha256 {_sha256(args.resume)})"
        if resume
        else "start at the priors"
    )
    summary = {
        "method": f"scipy.optimize.least_squares on the noise-free model, {start}, "
        "staged (thermaxis.twin.stages.STAGES), then the compass search on the workflow's "
        "faithfulness table (thermaxis.twin.polish)",
        **{f"rms_{name}": round(value, 4) for name, value in result.rms.items()},
        **{name: round(value, 4) for name, value in result.summary.items()},
        "evaluations": result.evaluations,
        # A resumed leg's record goes on from the one it resumed.
        "stages": (_recorded_stages(args.resume) if resume else [])
        + [
            {key: value for key, value in stage.items() if key != "seconds"}
            for stage in result.stages
        ],
    }
    mdl.save_params(result.params, args.params, summary)
    generate_dataset(args.out, args.truth, args.params)
    figures = ", ".join(f"{name} {value:.3f}" for name, value in result.rms.items())
    seconds = ", ".join(f"{s['name']} {s['seconds']:.0f} s" for s in result.stages)
    print(
        f"calibrated (noise-free RMS): {figures}; stages: {seconds}; "
        f"wrote {args.params} and regenerated {args.out}"
    )
    return 0


def _conflicts(args) -> int:
    """The experiments on the conflicts between the calibration targets, as markdown."""
    from .calibration import pipeline_observables
    from .conflicts import conflicts, conflicts_markdown

    experiments = conflicts(
        pipeline_observables, progress=lambda line: print(line, file=sys.stderr)
    )
    args.out.write_text(conflicts_markdown(experiments), encoding="utf-8")
    print(f"wrote {args.out}")
    return 0


def _scale(args) -> int:
    """A large simulated benchmark dataset of the size asked (not committed)."""
    from .scale import ScaleSpec, generate_scale

    spec = ScaleSpec(
        args.runs,
        args.sensors,
        args.positions,
        args.hours,
        args.rate_hz,
        args.seed,
        60.0 * args.measurement_min,
        args.name,
    )
    try:
        generate_scale(args.out, spec)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
