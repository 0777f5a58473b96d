"""bench.json and bench.md: each figure beside the project's target."""

from __future__ import annotations

import json
import os
from dataclasses import asdict, fields
from pathlib import Path

from tools.bench import records as bench_records
from tools.bench.measure import Measurement, _add_jobs
from tools.bench.scaling import GROWTH_SHAPES, SCALE_SHAPES, fit_scaling

TARGETS = {
    "results_cold": "cold full regeneration of the twin <= 30 s",
    "results_noop": "no-op rerun <= 1.25 x a one-rule workflow's no-op",
    "sweep_default": "default sweep (all configurations x all folds) <= 15 s",
    "scale_one_position_43": "43 runs x 30 measurements x 24 sensors, one position, default config, end to end <= 5 min, peak RSS < 2 GB",
    "scale_one_position_86": "86 runs take <= 2.3 x the 43 runs' time, peak RSS < 2 GB",
    "test_suite": "make test after set-up <= 180 s",
    "dryrun_twin": "dry run of the twin <= the one-rule dry run + 2 s CPU",
    "startup_slurm": "one-rule no-op with the Slurm plugin installed <= 1.5 x without it",
    "sweep_subsets": "exhaustive 3-of-22 subsets, 5 runs, single position <= 30 s",
    "twin_calibrate": "make twin-calibrate (its last leg, the polish through the pipeline) <= 10 min on 2 cores",
}


def finish(doc: dict, measurements: list[Measurement], out: Path) -> dict:
    """Add the measurements, the scaling fits and the targets to ``doc``; write bench.json and bench.md."""
    doc["measurements"] = [{**asdict(m), "ok": m.ok} for m in measurements]
    doc.pop("scale_fit", None)
    for shape in SCALE_SHAPES:
        scale = [m for m in measurements if m.name.startswith(f"scale_{shape}_") and m.ok]
        if len({m.runs for m in scale}) >= 2:
            doc.setdefault("scale_fit", {})[shape] = {
                "wall": asdict(fit_scaling([m.runs for m in scale], [m.wall_s for m in scale])),
                "cpu": asdict(
                    fit_scaling([m.runs for m in scale], [m.cpu_s for m in scale], "CPU time")
                ),
            }
    doc["targets"] = _targets(measurements) + [
        {
            "target": f"{q['record']}: recommendation <= {bench_records.RECORD_TARGETS['references']} x the better "
            f"plain reference and <= {bench_records.RECORD_TARGETS['paper']} x the paper's configuration",
            "measured": f"{q['recommended_rmse_um']:.2f} um: {q['vs_references']:.2f} x "
            f"{min(q['baseline_rmse_um'], q['evidence_rmse_um']):.2f}, "
            f"{q['vs_paper']:.2f} x {q['paper_rmse_um']:.2f}",
            "met": q["met"],
        }
        for q in doc.get("records", [])
    ]
    out.mkdir(parents=True, exist_ok=True)
    (out / "bench.json").write_text(
        json.dumps(doc, indent=1, sort_keys=True) + "\n", encoding="utf-8"
    )
    (out / "bench.md").write_text(bench_markdown(doc), encoding="utf-8")
    return doc


def render(out: Path) -> dict:
    """Re-derive the fits, targets and bench.md from an existing ``out/bench.json`` (nothing is rerun)."""
    path = out / "bench.json"
    if not path.is_file():
        raise ValueError(f"{path}: not found; run the benchmark first")
    doc = json.loads(path.read_text(encoding="utf-8"))
    names = {f.name for f in fields(Measurement)}
    measurements = [
        Measurement(**{k: v for k, v in d.items() if k in names}) for d in doc["measurements"]
    ]
    for m in measurements:
        _add_jobs(m)
    return finish(doc, measurements, out)


def _peak_mib(m: Measurement) -> float:
    """Peak RSS of the process tree, else of the largest process."""
    return m.peak_tree_rss_mib if m.peak_tree_rss_mib is not None else m.peak_rss_mib


def _targets(measurements: list[Measurement]) -> list[dict]:
    by_name = {m.name: m for m in measurements}
    return _workflow_targets(by_name) + _scale_targets(by_name)


def _target(name: str, met: bool, measured: str) -> dict:
    return {"target": TARGETS[name], "measured": measured, "met": met}


def _ratio_target(name, m, floor, limit, met=True, note="") -> dict:
    """A target on the wall time against a floor's: at most ``limit`` times it."""
    ratio = m.wall_s / floor.wall_s
    return _target(
        name,
        m.ok and floor.ok and ratio <= limit and met,
        f"{m.wall_s:.1f} s vs {floor.wall_s:.1f} s: {ratio:.2f} x{note}",
    )


def _workflow_targets(by_name: dict[str, Measurement]) -> list[dict]:
    """The workflow's targets: make results cold and with nothing to do, the sweep, the dry
    run, the test suite."""
    rows = []
    if "results_cold" in by_name:
        m = by_name["results_cold"]
        rows.append(_target("results_cold", m.ok and m.wall_s <= 30.0, f"{m.wall_s:.1f} s"))
    if "results_noop" in by_name and "one_rule_noop" in by_name:
        params = by_name.get("one_rule_params_noop")
        note = (
            f"; against the one rule with one params entry ({params.wall_s:.1f} s): "
            f"{by_name['results_noop'].wall_s / params.wall_s:.2f} x"
            if params is not None
            else ""
        )
        rows.append(
            _ratio_target(
                "results_noop", by_name["results_noop"], by_name["one_rule_noop"], 1.25, note=note
            )
        )
    if "sweep_default" in by_name:
        m = by_name["sweep_default"]
        n = m.extra.get("configurations", 0)
        rows.append(_target("sweep_default", m.ok and m.wall_s <= 15.0,
                            f"{n} configurations x {m.extra.get('folds', '?')} folds in {m.wall_s:.1f} s"))  # fmt: skip
    if "dryrun_twin" in by_name and "dryrun_one_rule" in by_name:
        m, floor = by_name["dryrun_twin"], by_name["dryrun_one_rule"]
        extra = m.cpu_s - floor.cpu_s
        rows.append(_target("dryrun_twin", m.ok and extra <= 2.0,
                            f"{m.wall_s:.1f} s wall, {m.cpu_s:.1f} s CPU vs {floor.wall_s:.1f} s, {floor.cpu_s:.1f} s: "
                            f"+{m.wall_s - floor.wall_s:.1f} s wall, +{extra:.1f} s CPU"))  # fmt: skip
    if "test_suite" in by_name:
        m = by_name["test_suite"]
        rows.append(_target("test_suite", m.ok and m.wall_s <= 180.0, f"{m.wall_s:.1f} s"))
    return rows


def _scale_targets(by_name: dict[str, Measurement]) -> list[dict]:
    """The targets of the large datasets, the subset sweep, the calibration and Slurm's start."""
    rows = []
    if "scale_one_position_43" in by_name:
        m = by_name["scale_one_position_43"]
        peak = _peak_mib(m)
        rows.append(_target("scale_one_position_43", m.ok and m.wall_s <= 300.0 and peak < 2000.0,
                            f"{m.wall_s:.1f} s, peak {peak:.0f} MiB"))  # fmt: skip
    if "scale_one_position_86" in by_name and "scale_one_position_43" in by_name:
        m, base = by_name["scale_one_position_86"], by_name["scale_one_position_43"]
        peak = _peak_mib(m)
        rows.append(
            _ratio_target(
                "scale_one_position_86", m, base, 2.3, peak < 2000.0, f", peak {peak:.0f} MiB"
            )
        )
    if "sweep_subsets" in by_name:
        m = by_name["sweep_subsets"]
        rows.append(_target("sweep_subsets", m.ok and m.wall_s <= 30.0, f"{m.wall_s:.1f} s"))
    if "twin_calibrate" in by_name:
        m = by_name["twin_calibrate"]
        rows.append(
            _target(
                "twin_calibrate",
                m.ok and m.wall_s <= 600.0,
                f"{m.wall_s:.1f} s on {os.cpu_count()} cores; "
                f"committed parameters reproduced: {m.extra.get('reproduces_committed')}",
            )
        )
    if "startup_noop_slurm" in by_name and "startup_noop_venv" in by_name:
        rows.append(
            _ratio_target(
                "startup_slurm", by_name["startup_noop_slurm"], by_name["startup_noop_venv"], 1.5
            )
        )
    return rows


def bench_markdown(doc: dict) -> str:
    """bench.md: the machine, one row per measurement, the scaling statement, the targets."""
    machine = doc["machine"]
    lines = [
        "# thermaxis benchmark",
        "",
        f"Machine: {machine['usable_cores']} usable cores ({machine['cpu_count']} CPUs), "
        f"{machine.get('memory_gib')} GiB memory, {machine['platform']}, Python {machine['python']}. "
        f"Snakemake ran with `--cores {doc['settings']['cores']}`. Load average at start "
        f"{machine['load_average_at_start']}, at end {machine.get('load_average_at_end')} "
        "(other work on the machine inflates wall times).",
        "",
        "| measurement | wall (s) | CPU (s) | peak RSS, largest process (MiB) | peak RSS, process tree (MiB) | jobs | ok | what |",
        "|---|---:|---:|---:|---:|---:|---|---|",
    ]
    for m in doc["measurements"]:
        tree = "" if m["peak_tree_rss_mib"] is None else f"{m['peak_tree_rss_mib']:.0f}"
        jobs = m["extra"].get("jobs")
        what = m["description"]
        if "configurations" in m["extra"]:
            what += f"; {m['extra']['configurations']} configurations x {m['extra']['folds']} folds"
        lines.append(
            f"| {m['name']} | {m['wall_s']:.1f} | {m['cpu_s']:.1f} | {m['peak_rss_mib']:.0f} | {tree} | "
            f"{'' if jobs is None else jobs} | {'yes' if m['ok'] else 'NO'} | {what} |"
        )
    for shape, fit in doc.get("scale_fit", {}).items():
        lines += ["", f"Scaling of the scale series {shape}: {fit['wall']['statement']}.",
                  f"{fit['cpu']['statement']}."]  # fmt: skip
    for key, what in (
        ("records", "the records at hand"),
        ("dev_records", "the SIMULATED development records (tools.bench.records.DEV_RECORDS)"),
    ):
        if doc.get(key):
            lines += _quality_table(doc[key], what)
    if doc.get("targets"):
        lines += ["", "| target | measured | met |", "|---|---|---|"]
        lines += [
            f"| {t['target']} | {t['measured']} | {'yes' if t['met'] else 'no'} |"
            for t in doc["targets"]
        ]
    shapes = doc.get("settings", {}).get("scale_shapes") or {
        shape: SCALE_SHAPES[shape] for shape in GROWTH_SHAPES
    }
    lines += [
        "",
        "Scale runs: SIMULATED twin-generated datasets shaped like a measured record ("
        + "; ".join(_shape_phrase(name, spec) for name, spec in shapes.items())
        + "), the default configuration end to end, from cleaning to the index (every "
        "algorithm, every run held out once, every figure and report). Peak RSS of the process "
        "tree is sampled every 0.2 s (psutil).",
    ]
    return "\n".join(lines) + "\n"


def _quality_table(rows: list, what: str) -> list:
    """Markdown lines: each record's recommendation beside the references and the paper's."""
    lines = [
        "",
        "Mean held-out RMSE (µm, leave-one-condition-out) of the recommendation, the two plain "
        "references (the ridge with lags `baseline-ridge+lags`, the evidence ridge `evidence-ridge`) "
        f"and the paper's configuration, on the same folds, on {what} (tools/bench/records.py):",
        "",
        "| record | folds | recommendation | ridge with lags | evidence ridge | paper's configuration "
        "| vs better reference | vs paper | verdict (improved / worsened of held-out runs, the "
        "untested if any, sign test p) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    return lines + [
        f"| {q['record']} | {q['folds']} | {q['recommended_rmse_um']:.2f} | {q['baseline_rmse_um']:.2f} | "
        f"{q['evidence_rmse_um']:.2f} | {q['paper_rmse_um']:.2f} | {q['vs_references']:.2f} | "
        f"{q['vs_paper']:.2f} | {_verdict_cell(q)} |"
        for q in rows
    ]


def _verdict_cell(q: dict) -> str:
    """The compensation's verdict in words and its counts (improved / worsened of held out,
    and the runs the fallback withheld it from throughout, when there are any)."""
    untested = f", {q['untested_runs']} untested" if q.get("untested_runs") else ""
    return (
        f"{q['verdict'].replace('_', ' ')} ({q['improved_runs']} / {q['worsened_runs']} of "
        f"{q['held_out_runs']}{untested}, p = {q['sign_test_p']:.2g})"
    )


def _shape_phrase(name: str, spec: dict) -> str:
    """One scale shape in words, from the generator's settings (tools.bench.scaling)."""
    measurements = int(spec["hours"] * 60 // spec["measurement_min"])
    return (
        f"{name}: {spec['sensors']} sensors logged every {1 / spec['rate_hz']:g} s, "
        f"{measurements} measurements per run, {spec['positions']} position(s)"
    )
