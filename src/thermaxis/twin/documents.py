"""Dataset documents of the twin: dataset.yaml, runs.tsv and README.md.

README.md is the template ``thermaxis/twin/templates/README.md.tmpl``, filled with the
instruments, seeded faults and missing reading the twin's own modules define; the
calibration report (CALIBRATION.md) is :mod:`thermaxis.twin.report`.
"""

from __future__ import annotations

from pathlib import Path

from thermaxis.templates import fill

from . import conditions as cond
from . import faults
from . import model as mdl
from .observe import (
    HMI_CLOCK_OFFSET_S,
    INTERFEROMETER,
    SENSORS,
    SOURCES,
    WIRELESS_JITTER_S,
    WIRELESS_PERIOD_S,
)

__all__ = ["write_dataset_docs"]


PROVENANCE = (
    "SIMULATED. The paper's measurements are not public, so this dataset comes from "
    "thermaxis.twin, a lumped thermal network of the X axis of a worm-wheel gear grinding "
    "machine (ball screw with a hidden core temperature, nut, bearing seat, carriages, "
    "motor, bed core and walls, screw sleeve; workshop air as a boundary) driven by the "
    "reciprocating feeds of the paper's four experiments (2000-8000 mm/min) and by a "
    "workshop-air profile per experiment that spans Table 1's range (cooling switched on "
    "in experiments 3 and 4). Twelve PT100 sensors at the locations of Table 2 observe the "
    "network through their own mounting, lag, offset and noise, and the positioning error "
    "(geometric slope and pitch error, screw expansion proportional to position, "
    "position-independent drift of the structure, XL-80-class noise, reversal error) is "
    "read at 14 targets in a forward and a backward pass, 8 times per run, never "
    "re-zeroed. Heat inputs, expansion and drift gains, some effective capacities, each "
    "run's initial temperatures and the mountings and offsets of the sensors the paper's "
    "fitted models use were fitted so that the decoupled k and b of the 32 measurements "
    "match the paper's Table 5 and the paper's Eq. 8 and Eq. 9, applied to the twin's "
    "temperatures, give back its errors, k and b (see CALIBRATION.md). The logs carry "
    "realistic faults listed in README.md."
)


def _yaml_quote(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _dataset_yaml() -> str:
    lines = [
        "# Written by `python -m thermaxis.twin generate` -- do not edit by hand.",
        "name: twin",
        "reproduces: xu2023",
        "ambient_sensor: T10",
        "temperature_kind: absolute",
        "description: >-",
        "  Thermal twin of the X axis in Xu et al.: four runs E1-E4 (the paper's experiments",
        "  1-4, reciprocating at 2000, 4000, 6000 and 8000 mm/min), 12 temperature sensors from",
        "  three acquisition sources and 8 unzeroed interferometer measurements per run.",
        "provenance:",
        "  kind: simulated",
        "  citation: "
        + _yaml_quote(
            "thermaxis.twin, calibrated to Xu K., Li G., Li Z., Wang Z., Miao E., Research on "
            "decoupling and step-by-step modelling of thermal positioning error of the linear "
            "axis, Chinese Journal of Scientific Instrument, DOI 10.19650/j.cnki.cjsi.J2209628 "
            "(Tables 1, 2 and 5, Eq. 8 and Eq. 9)"
        ),
        "  generator: python -m thermaxis.twin generate",
        "  description: " + _yaml_quote(PROVENANCE),
        "axis:",
        "  name: X",
        "  machine: worm-wheel gear grinding machine (simulated)",
        "  targets_mm: [" + ", ".join(f"{x:.0f}" for x in cond.TARGETS_MM) + "]",
        "  interferometer: laser interferometer, XL-80 class (+-0.5 um/m), simulated",
        "  datum: zeroed once at 185 mm just before M1; later measurements are not re-zeroed",
        "sensors:",
    ]
    for s in SENSORS:
        lines.append(f"  - {{id: {s.id}, location: {_yaml_quote(s.location)}, source: {s.source}}}")
    lines.append("sources:")
    for name, note, offset in SOURCES:
        lines += [
            f"  - name: {name}",
            f"    clock_note: {_yaml_quote(note)}",
            f"    clock_offset_s: {offset:g}",
        ]
    return "\n".join(lines) + "\n"


def _runs_tsv() -> str:
    lines = ["run\tcondition\tfeed_mm_min\tdescription"]
    for c in cond.CONDITIONS:
        lines.append(f"{c.run}\t{c.condition}\t{c.feed_mm_min:.0f}\t{c.description}")
    return "\n".join(lines) + "\n"


def _readme() -> str:
    """README.md of the embedded dataset: its runs, files, instruments and seeded faults."""
    return fill(
        "thermaxis.twin",
        "README.md.tmpl",
        **_instrument_values(),
        **_fault_values(),
        **_missing_reading_values(),
    )


def _instrument_values() -> dict:
    """The sources' cadences and the sensors' and interferometer's behaviour, as the README states them."""
    return dict(
        wireless_period_s=f"{WIRELESS_PERIOD_S:g}",
        wireless_jitter_s=f"{WIRELESS_JITTER_S:g}",
        hmi_clock_offset_s=f"{HMI_CLOCK_OFFSET_S:g}",
        lag_min_s=f"{min(s.lag_s for s in SENSORS):g}",
        lag_max_s=f"{max(s.lag_s for s in SENSORS):g}",
        offset_limit_c=f"{mdl.OFFSET_LIMIT_C:g}",
        calibrated_sensors=", ".join(mdl.MOUNTING_SURFACES),
        reading_noise_um=f"{INTERFEROMETER.reading_noise_um:g}",
        scale_error_um_per_m=f"{INTERFEROMETER.scale_error_um_per_m:g}",
        reversal_um=f"{abs(INTERFEROMETER.reversal_um):g}",
    )


def _within_measurement(run: str, minute: float) -> str:
    """Which measurement's window a fault falls in, if any, for the fault table."""
    m = faults.measurement_at(run, minute)
    return f" (inside M{m:02d}'s window)" if m else ""


def _fault_values() -> dict:
    """The rows and cells of the README's table of seeded faults (thermaxis.twin.faults)."""
    oc_run, oc_sensor, oc_min = faults.OPEN_CIRCUIT
    out_run, out_first, out_last = faults.WIRELESS_OUTAGE
    spike_rows = "\n".join(
        f"| {s.run} | box | {s.sensor} | single-sample spike of {s.delta_c:+.1f} degC at {s.minute:g} min"
        f"{_within_measurement(s.run, s.minute)} |"
        for s in faults.SPIKES
    )
    duplicate_rows = "\n".join(
        f"| {run} | box | all | {n} row(s) from {minute:g} min written twice (identical time and values)"
        f"{_within_measurement(run, minute)} |"
        for run, minute, n in faults.DUPLICATED_ROWS
    )
    return dict(
        spike_rows=spike_rows,
        duplicate_rows=duplicate_rows,
        open_circuit_run=oc_run,
        open_circuit_sensor=oc_sensor,
        open_circuit_c=f"{faults.OPEN_CIRCUIT_C:.3f}",
        open_circuit_min=f"{oc_min:g}",
        open_circuit_where=_within_measurement(oc_run, oc_min),
        wireless_loss=f"{faults.WIRELESS_LOSS_PROBABILITY:.0%}",
        outage_run=out_run,
        outage_first_min=f"{out_first:g}",
        outage_last_min=f"{out_last:g}",
    )


def _missing_reading_values() -> dict:
    """The one interferometer capture the twin leaves out, as README.md and CALIBRATION.md name it."""
    run, measurement, direction, position = faults.MISSING_READING
    return dict(
        missing_run=run,
        missing_measurement=f"{measurement:02d}",
        missing_pass=direction,
        missing_position_mm=f"{position:g}",
    )


def write_dataset_docs(root: Path | str) -> None:
    """dataset.yaml, runs.tsv and README.md of the embedded dataset."""
    root = Path(root)
    (root / "dataset.yaml").write_text(_dataset_yaml(), encoding="utf-8")
    (root / "runs.tsv").write_text(_runs_tsv(), encoding="utf-8")
    (root / "README.md").write_text(_readme(), encoding="utf-8")
