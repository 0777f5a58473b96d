"""Dataset documents (dataset.yaml, runs.tsv, README.md) and the calibration report.

The calibration report is computed from the RAW files just written, by the pipeline's
own library with the default configuration: :func:`thermaxis.cleaning.run.clean_and_assemble_run`
(cleaning, pass mean, window-mean temperatures), :func:`thermaxis.method.decouple.decouple_table`
(k and b, origin 185 mm) and, for the held-out fold E4, the workflow's
:func:`thermaxis.method.folds.select_for_fold` and :func:`~thermaxis.method.folds.evaluate_configuration`.
The held-out results are reported, never fitted to.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from thermaxis.cleaning.run import clean_and_assemble_run, model_inputs
from thermaxis.config import Settings, load_config
from thermaxis.method.decouple import decouple_table
from thermaxis.method.folds import evaluate_configuration, select_for_fold
from thermaxis.dataset.reader import load_dataset, read_run
from thermaxis.paper.published import load_table
from . import conditions as cond
from . import faults
from . import model as mdl
from .fit import PAPER_TABLE5, RunObservables, acceptance_bounds, objective_weights, target_residuals
from .observe import HMI_CLOCK_OFFSET_S, INTERFEROMETER, SENSORS, SOURCES, WIRELESS_JITTER_S, WIRELESS_PERIOD_S
from .published import PublishedTargets, published_targets

__all__ = [
    "PipelineView",
    "pipeline_view",
    "write_dataset_docs",
    "write_calibration_report",
]


# --------------------------------------------------------------------------- documents

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
        lines += [f"  - name: {name}", f"    clock_note: {_yaml_quote(note)}", f"    clock_offset_s: {offset:g}"]
    return "\n".join(lines) + "\n"


def _runs_tsv() -> str:
    lines = ["run\tcondition\tfeed_mm_min\tdescription"]
    for c in cond.CONDITIONS:
        lines.append(f"{c.run}\t{c.condition}\t{c.feed_mm_min:.0f}\t{c.description}")
    return "\n".join(lines) + "\n"


def _readme() -> str:
    def where(run: str, minute: float) -> str:
        m = faults.measurement_at(run, minute)
        return f" (inside M{m:02d}'s window)" if m else ""

    spikes = "\n".join(
        f"| {s.run} | box | {s.sensor} | single-sample spike of {s.delta_c:+.1f} degC at {s.minute:g} min{where(s.run, s.minute)} |"
        for s in faults.SPIKES
    )
    dups = "\n".join(
        f"| {run} | box | all | {n} row(s) from {minute:g} min written twice (identical time and values){where(run, minute)} |"
        for run, minute, n in faults.DUPLICATED_ROWS
    )
    oc_run, oc_sensor, oc_min = faults.OPEN_CIRCUIT
    out_run, out_first, out_last = faults.WIRELESS_OUTAGE
    miss_run, miss_meas, miss_dir, miss_pos = faults.MISSING_READING
    return f"""\
# `twin` -- the embedded default dataset (SIMULATED)

**These are not measurements.** The paper's data are not public; this dataset is
generated by `thermaxis.twin` (`make twin`, i.e. `python -m thermaxis.twin generate`)
from the committed parameters `src/thermaxis/twin_params.json`, byte for byte. How
the parameters were fitted to the paper's Table 5, Eq. 8 and Eq. 9, and how close the
twin comes, is in [CALIBRATION.md](CALIBRATION.md).

## Runs

`E1` ... `E4` are the paper's experiments 1-4 (Table 1): reciprocating motion at 2000,
4000, 6000 and 8000 mm/min, workshop air 30.4-31.6, 30.1-31.2, 27.4-28.3 and
28.8-30.5 degC; in E3 and E4 the workshop cooling is switched on during the run and the
air falls. Each run has 8 measurements about 23 min apart (0 ... 161 min; M1 is the
cold state, the axis reciprocates between measurements). Dates are fictitious (one day
per run, March 2022).

## Files

- `<run>/temperatures/box.csv`: T1-T10 from the acquisition box, every 10 s, `%.3f`.
- `<run>/temperatures/wireless.csv`: T11 (nut), wireless, irregular ~30 s packets
  ({WIRELESS_PERIOD_S:g} +- {WIRELESS_JITTER_S:g} s), time with milliseconds, `%.2f`.
- `<run>/temperatures/hmi.csv`: T12 (motor winding) read from the CNC HMI every 60 s of
  the HMI's own clock, quantised to 0.1 degC. The HMI clock runs {HMI_CLOCK_OFFSET_S:g} s behind the box:
  `clock_offset_s: {HMI_CLOCK_OFFSET_S:g}` in dataset.yaml (add it to the HMI times).
- `<run>/errors/M01.csv` ... `M08.csv`: one interferometer measurement each: 14 targets
  185 ... 445 mm, forward pass (`+`) then backward pass (`-`), one capture every
  6 s, error in um (`%.4f`). The interferometer was zeroed ONCE, at 185 mm about 30 s
  before M1; later measurements carry the drift ("unzeroed").
- Temperature logs start 10 min before M1 and end 10 min after M8. The box and the
  interferometer share the reference clock; the wireless gateway is synchronised to it.

## Instrument behaviour (not faults)

- Sensors read their mounting surface (a mix of the part they are clamped to, its
  neighbours and the air) through a first-order lag ({min(s.lag_s for s in SENSORS):g}-{max(s.lag_s for s in SENSORS):g} s), with a
  fixed calibration offset (within PT100 class B, +-{mdl.OFFSET_LIMIT_C:g} degC at 30 degC) and white noise.
  The mountings of {", ".join(mdl.MOUNTING_SURFACES)} (the sensors of the paper's Eq. 8 and Eq. 9) are
  calibrated (CALIBRATION.md).
- The interferometer adds noise of {INTERFEROMETER.reading_noise_um:g} um per capture, a per-measurement
  scale error (air compensation, {INTERFEROMETER.scale_error_um_per_m:g} um/m 1 sigma, clipped to +-0.5 um/m) and
  a reversal error: the backward pass reads {abs(INTERFEROMETER.reversal_um):g} um lower.

## Seeded faults (what a cleaning stage must handle)

| run | source | sensor | fault |
|---|---|---|---|
{spikes}
| {oc_run} | box | {oc_sensor} | open circuit: one reading of {faults.OPEN_CIRCUIT_C:.3f} at {oc_min:g} min{where(oc_run, oc_min)} (out of the PT100 range) |
{dups}
| all | wireless | T11 | about {faults.WIRELESS_LOSS_PROBABILITY:.0%} of the packets lost (no row) |
| {out_run} | wireless | T11 | link outage from {out_first:g} to {out_last:g} min (no rows) |
| all | hmi | T12 | 60 s sampling, 0.1 degC quantisation, clock {HMI_CLOCK_OFFSET_S:g} s behind |
| {miss_run} | errors | M{miss_meas:02d} | the capture at {miss_pos:g} mm of the `{miss_dir}` pass is missing |

Times of the faults are minutes from the start of M1 (rows nearest to that minute).
The fault-free sensor temperatures and the noise-free k and b are in
`data/twin_truth/` (tests only; the modelling code never reads them).
"""


def write_dataset_docs(root: Path | str) -> None:
    """dataset.yaml, runs.tsv and README.md of the embedded dataset."""
    root = Path(root)
    (root / "dataset.yaml").write_text(_dataset_yaml(), encoding="utf-8")
    (root / "runs.tsv").write_text(_runs_tsv(), encoding="utf-8")
    (root / "README.md").write_text(_readme(), encoding="utf-8")


# --------------------------------------------------------------------------- calibration

#: The held-out comparisons of the paper: (approach, algorithm, paper table).
HELDOUT = (("decoupled", "mlr", 7), ("decoupled", "svr", 8), ("pointwise", "mlr", 4))
#: The twin before it was calibrated to Eq. 8 and Eq. 9 too (to Table 5 only), fold E4 with the default
#: configuration: ``snakemake results/twin/tables/metrics.csv`` at commit fac73bc.
#: A record of that run for comparison; nothing is computed from it.
PREVIOUS_TWIN_HELDOUT = {
    ("decoupled", "mlr", "k"): (4.477, 7.785, 3.505),
    ("decoupled", "mlr", "b"): (0.895, 1.606, 0.718),
    ("decoupled", "mlr", "error"): (1.057, 1.877, 0.913),
    ("decoupled", "svr", "k"): (7.288, 10.684, 7.137),
    ("decoupled", "svr", "b"): (1.532, 2.554, 1.256),
    ("decoupled", "svr", "error"): (2.273, 4.179, 1.946),
    ("pointwise", "mlr", "error"): (2.527, 5.382, 2.152),
}
PREVIOUS_TWIN_SELECTION = {"k": "T3, T6, T11", "b": "T1, T9, T11", "pointwise": "T1, T7, T9"}


@dataclass(frozen=True)
class PipelineView:
    """The twin as the pipeline assembles it (default configuration)."""

    kb: pd.DataFrame  # run, measurement, time_min, k_um_per_m, b_um, r2, rms_um, n_targets
    X: pd.DataFrame  # run, measurement, time_min, absolute temperature per sensor
    Y: pd.DataFrame  # pass-mean unzeroed error per target (columns, mm)
    ambient: pd.DataFrame  # run, min, max of the cleaned ambient sensor over the log
    config: dict
    settings: Settings

    def observables(self) -> dict[str, RunObservables]:
        out = {}
        for run, rows in self.X.groupby("run", sort=True):
            kb = self.kb[self.kb["run"] == run]
            out[run] = RunObservables(
                k=kb["k_um_per_m"].to_numpy(),
                b=kb["b_um"].to_numpy(),
                curve=self.Y.loc[rows.index].to_numpy(dtype=float),
                temperatures={s: rows[s].to_numpy() for s in rows.columns if s not in ("run", "measurement", "time_min")},
            )
        return out


def pipeline_view(root: Path | str) -> PipelineView:
    """Clean, assemble and decouple the raw dataset under ``root`` with the default config."""
    config = load_config()
    dataset = load_dataset(root)
    # The ambient sensor is the dataset's own declaration unless the config overrides it.
    config["ambient_sensor"] = config.get("ambient_sensor") or dataset.ambient_sensor
    settings = Settings.from_config(config)
    tables = [clean_and_assemble_run(dataset, read_run(dataset, run), settings.cleaning) for run in dataset.run_ids]
    errors = pd.concat([t.errors for t in tables], ignore_index=True)
    kb, _ = decouple_table(errors, degree=1)  # Table 5: the paper's straight line
    kb["n_targets"] = errors.dropna(subset=["error_um"]).groupby(["run", "measurement"]).size().to_numpy()
    X, Y = model_inputs(errors, pd.concat([t.temperatures for t in tables], ignore_index=True))
    sensor = config["ambient_sensor"]
    ambient = pd.DataFrame(
        [(t.run, t.series[sensor].min(), t.series[sensor].max()) for t in tables], columns=["run", "min", "max"]
    )
    return PipelineView(kb=kb, X=X, Y=Y, ambient=ambient, config=config, settings=settings)


def heldout_results(view: PipelineView) -> tuple[pd.DataFrame, dict[str, str]]:
    """The paper's fold (train on the other runs, predict it) as the workflow runs it."""
    fold = view.config["paper_fold"]
    s = view.settings
    selection = select_for_fold(view.X, view.Y, fold, s.selection, s.decoupling.degree)
    metrics = pd.concat(
        [
            evaluate_configuration(
                view.X, view.Y, fold, approach, algorithm, selection, s.models, s.decoupling.degree
            ).metrics
            for approach, algorithm, _ in HELDOUT
        ],
        ignore_index=True,
    )
    chosen = {"k": selection.k_sensors, "b": selection.b_sensors, "pointwise": selection.pointwise}
    return metrics, {name: ", ".join(sensors) for name, sensors in chosen.items()}


def _rms(values) -> float:
    values = np.ravel(np.asarray(values, dtype=float))
    return float(np.sqrt(np.nanmean(np.square(values))))


def _comparison(kb: pd.DataFrame) -> pd.DataFrame:
    out = kb.copy()
    out["k_paper"] = [PAPER_TABLE5[r][0][m - 1] for r, m in zip(out["run"], out["measurement"])]
    out["b_paper"] = [PAPER_TABLE5[r][1][m - 1] for r, m in zip(out["run"], out["measurement"])]
    out["dk"] = out["k_um_per_m"] - out["k_paper"]
    out["db"] = out["b_um"] - out["b_paper"]
    return out


def _figure(table: pd.DataFrame, eq9: dict[str, dict[str, np.ndarray]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {"E1": "tab:blue", "E2": "tab:orange", "E3": "tab:green", "E4": "tab:red"}
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), dpi=100, sharex=True)
    for run, group in table.groupby("run", sort=True):
        colour = colours.get(run, "k")
        for col, (twin, paper, key) in enumerate((("k_um_per_m", "k_paper", "eq9_k"), ("b_um", "b_paper", "eq9_b"))):
            axes[0, col].plot(group["time_min"], group[twin], "o-", color=colour, label=f"{run} twin")
            axes[0, col].plot(group["time_min"], group[paper], "s--", mfc="none", color=colour, label=f"{run} Table 5")
            axes[1, col].plot(group["time_min"], group[twin], "o-", color=colour, label=f"{run} twin")
            axes[1, col].plot(
                group["time_min"], group[twin] + eq9[run][key], "^:", mfc="none", color=colour, label=f"{run} Eq. 9"
            )
    for row, what in enumerate(("Table 5", "Eq. 9 on the twin's temperatures")):
        axes[row, 0].set_ylabel(f"slope k (um/m)\nvs {what}")
        axes[row, 1].set_ylabel(f"intercept b (um)\nvs {what}")
        axes[row, 0].legend(ncol=2, fontsize=6)
    for ax in axes.ravel():
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("time from M1 (min)")
    fig.suptitle("SIMULATED twin (raw files through the pipeline) vs the paper")
    fig.tight_layout()
    fig.savefig(path, metadata={"Software": None})
    plt.close(fig)


def _parameter_tables(params: mdl.TwinParams) -> str:
    physical = [n for n in mdl.GLOBAL_PARAMETERS if not n.startswith(("mount_", "offset_"))]
    rows = "\n".join(
        f"| `{name}` | {params.values[name]:.4g} | {mdl.GLOBAL_PARAMETERS[name].lower:g} ... "
        f"{mdl.GLOBAL_PARAMETERS[name].upper:g} | {mdl.GLOBAL_PARAMETERS[name].meaning} |"
        for name in physical
    )
    mountings = "\n".join(
        f"| {sensor} | {next(s.location for s in SENSORS if s.id == sensor)} | "
        + ", ".join(f"{name} {w:.2f}" for name, w in mdl.mounting(params.values, sensor)[0].items())
        + f" | {mdl.mounting(params.values, sensor)[1]:+.2f} | "
        + ", ".join(f"{name} {w:.2f}" for name, w in mdl.MOUNTING_DESIGN[sensor][0].items())
        + f" | {mdl.MOUNTING_DESIGN[sensor][1]:+.2f} |"
        for sensor in mdl.MOUNTING_SURFACES
    )
    header = "| run | " + " | ".join(f"`{n}`" for n in mdl.INITIAL_PARAMETERS) + " |"
    offsets = "\n".join(
        f"| {run} | " + " | ".join(f"{params.initial[run][n]:+.2f}" for n in mdl.INITIAL_PARAMETERS) + " |"
        for run in sorted(params.initial)
    )
    groups = "; ".join(f"`{n}`: {', '.join(nodes)}" for n, nodes in mdl.INITIAL_GROUPS.items())
    return f"""| parameter | value | bounds | meaning |
|---|---|---|---|
{rows}

Sensor mountings (weights of the surfaces each sensor reads, summing to 1, and the
calibration offset, bounded by PT100 class B at 30 degC, +-{mdl.OFFSET_LIMIT_C} degC), fitted
beside the design estimate they started from (the priors' centres):

| sensor | location | fitted weights | fitted offset degC | design weights | design offset degC |
|---|---|---|---|---|---|
{mountings}

Initial temperatures, K above the workshop air at the start of the log ({groups}):

{header}
|---|{"---|" * len(mdl.INITIAL_PARAMETERS)}
{offsets}"""


def _target_rows(residuals: dict, targets: PublishedTargets) -> str:
    pointwise = ", ".join(f"{x:g}" for x in targets.pointwise)
    # label, unit, and whether each run must also stay within twice the bound
    described = {
        "table5_k": ("Table 5 slope k (twin minus paper)", "um/m", False),
        "table5_b": ("Table 5 intercept b (twin minus paper)", "um", False),
        "eq9_k": ("Eq. 9 k on the twin's absolute T1, T6, T12 minus the twin's k", "um/m", True),
        "eq9_b": ("Eq. 9 b on the twin's relative T2, T7, T11 minus the twin's b", "um", True),
        "eq8": (f"Eq. 8 at {pointwise} mm on relative T1, T11, T12 minus the twin's error there", "um", True),
    }
    bounds, weights = acceptance_bounds(targets), objective_weights(targets)
    rows = []
    for name, (label, unit, per_run) in described.items():
        bound = bounds[name]
        overall = _rms([r[name] for r in residuals.values()])
        by_run = {run: _rms(r[name]) for run, r in residuals.items()}
        worst = max(by_run, key=by_run.get)
        met = overall <= bound and (not per_run or by_run[worst] <= 2 * bound)
        limit = f"RMS <= {bound:g}" + (f", each run <= {2 * bound:g}" if per_run else "")
        rows.append(
            f"| {label} | {1.0 / weights[name]:.3g} ({weights[name]:g} {unit}) | {limit} {unit} | "
            f"{overall:.3f} | {worst} {by_run[worst]:.3f} | {'yes' if met else '**no**'} |"
        )
    return "\n".join(rows)


def _per_run_rows(residuals: dict) -> str:
    names = ("table5_k", "table5_b", "eq9_k", "eq9_b", "eq8")
    return "\n".join(
        f"| {run} | " + " | ".join(f"{_rms(r[name]):.3f}" for name in names) + " |" for run, r in residuals.items()
    )


def _ambient_rows(view: PipelineView) -> str:
    table1 = load_table("table1").set_index("run")
    rows = []
    for r in view.ambient.itertuples():
        lo, hi = table1.loc[r.run, "ambient_min_c"], table1.loc[r.run, "ambient_max_c"]
        worst = max(abs(r.min - lo), abs(r.max - hi))
        rows.append(f"| {r.run} | {lo:.1f} ... {hi:.1f} | {r.min:.2f} ... {r.max:.2f} | {worst:.2f} | {'yes' if worst <= 0.2 else '**no**'} |")
    return "\n".join(rows)


def _rise_table(view: PipelineView) -> tuple[str, str]:
    sensors = [c for c in view.X.columns if c not in ("run", "measurement", "time_min")]
    rise = view.X.groupby("run", sort=True)[sensors].agg(lambda t: t.iloc[-1] - t.iloc[0]).T
    header = "| sensor | location | " + " | ".join(rise.columns) + " |\n|---|---|" + "---|" * len(rise.columns)
    location = {s.id: s.location for s in SENSORS}
    rows = "\n".join(
        f"| {sensor} | {location.get(sensor, '')} | " + " | ".join(f"{v:+.2f}" for v in rise.loc[sensor]) + " |"
        for sensor in rise.index
    )
    ambient = view.config["ambient_sensor"]
    machine = rise.drop(index=ambient)
    first = machine.columns[0]
    similarity = ", ".join(
        f"{run} {machine[first].corr(machine[run], method='spearman'):.2f}" for run in machine.columns[1:]
    )
    ranking = ", ".join(machine[first].sort_values(ascending=False).index[:4])
    return f"{header}\n{rows}", (
        f"Rank correlation (Spearman) of the rises of the machine's sensors (all but the ambient {ambient}) "
        f"with {first}'s: {similarity}. In {first} the largest rises are {ranking}."
    )


def _heldout_rows(metrics: pd.DataFrame) -> str:
    paper = load_table("prediction_metrics").set_index(["table", "approach", "algorithm", "target"])
    rows = []
    for approach, algorithm, table in HELDOUT:
        for target in ("k", "b", "error") if approach == "decoupled" else ("error",):
            new = metrics[
                (metrics["approach"] == approach) & (metrics["algorithm"] == algorithm) & (metrics["target"] == target)
            ].iloc[0]
            old = PREVIOUS_TWIN_HELDOUT[(approach, algorithm, target)]
            pub = paper.loc[(table, approach, algorithm, target)]
            rows.append(
                f"| {approach} {algorithm.upper()} | {target} | {table} | {pub['rmse']:.1f} / {pub['max_abs']:.1f} / {pub['mae']:.1f} | "
                f"{new['rmse']:.2f} / {new['max_abs']:.2f} / {new['mae']:.2f} | {old[0]:.2f} / {old[1]:.2f} / {old[2]:.2f} |"
            )
    return "\n".join(rows)


def _conclusions(metrics: pd.DataFrame) -> str:
    error = metrics[metrics["target"] == "error"].set_index(["approach", "algorithm"])["rmse"]
    decoupled = error[("decoupled", "mlr")] < error[("pointwise", "mlr")]
    svr = error[("decoupled", "svr")] < error[("decoupled", "mlr")]
    return (
        f"On the new twin, decoupled MLR {'beats' if decoupled else 'does not beat'} point-by-point MLR "
        f"(error RMSE {error[('decoupled', 'mlr')]:.2f} vs {error[('pointwise', 'mlr')]:.2f} um), and SVR "
        f"{'beats' if svr else 'does not beat'} MLR in the decoupled model "
        f"({error[('decoupled', 'svr')]:.2f} vs {error[('decoupled', 'mlr')]:.2f} um)."
    )


def _first_measurement_floor(targets: PublishedTargets) -> str:
    """What Eq. 8 and Eq. 9's b must miss at M1, where every relative temperature is 0."""
    last = max(targets.pointwise)
    lever = (last - cond.FIRST_TARGET_MM) / 1000.0
    const = targets.pointwise[last].const
    miss = {run: const - (b[0] + lever * k[0]) for run, (k, b) in PAPER_TABLE5.items()}
    miss_b = {run: targets.b.const - b[0] for run, (_, b) in PAPER_TABLE5.items()}
    return (
        f"At each run's first measurement every relative temperature is 0, so Eq. 8 predicts its constant, "
        f"{const:g} um at {last:g} mm, for every run, while Table 5 puts the error there (b + k * {lever:g} m) at "
        + ", ".join(f"{run} {const - m:.2f}" for run, m in miss.items())
        + " um: a miss of "
        + ", ".join(f"{m:+.2f}" for m in miss.values())
        + f" um that no temperature field can remove (RMS over the four first measurements {_rms(list(miss.values())):.2f} um). "
        f"Likewise Eq. 9 gives b = {targets.b.const:g} um at every first measurement, Table 5 "
        + ", ".join(f"{PAPER_TABLE5[r][1][0]:g}" for r in miss_b)
        + " um. "
        + _start_gap(targets)
    )


def _table4_tension(residuals: dict, targets: PublishedTargets, fold: str) -> str:
    """The printed Eq. 8 on the held-out run: the paper's Table 4 against the acceptance bound."""
    table4 = load_table("prediction_metrics").set_index(["table", "approach", "algorithm", "target"])
    published = table4.loc[(4, "pointwise", "mlr", "error")]
    held_out = residuals[fold]["eq8"]
    return (
        f"The printed Eq. 8 was fitted on the other runs and, by the paper's Table 4, predicts {fold} with an "
        f"error RMSE of {published['rmse']:g} um (max {published['max_abs']:g} um) over the 14 positions, whereas "
        f"the acceptance asks it to match every run, {fold} included, within {2 * targets.bound_error_um:g} um RMS "
        f"at the printed positions; the twin's {fold} misses by {_rms(held_out):.2f} um RMS (max "
        f"{np.nanmax(np.abs(held_out)):.2f} um) there: faithful to the bound, closer than Table 4 says the "
        "paper's own axis was."
    )


def _start_gap(targets: PublishedTargets) -> str:
    """How far from a uniform machine Eq. 9 puts E2's start against E1's."""
    table1 = load_table("table1").set_index("run")
    dk = PAPER_TABLE5["E2"][0][0] - PAPER_TABLE5["E1"][0][0]
    gain = sum(targets.k.coef.values())
    air = table1.loc["E2", "ambient_min_c"] - table1.loc["E1", "ambient_min_c"]
    return (
        f"E1 and E2 start in nearly the same air (Table 1 minima {air:+.1f} degC apart), yet Table 5's first "
        f"slopes differ by {dk:+.1f} um/m; Eq. 9's coefficients sum to {gain:.3f} um/m/K, so a machine at one "
        f"uniform temperature would have to start {dk / gain:+.2f} K apart. The twin meets this with the "
        "motor, the screw and the bed far from the air at the start of E1 and E2 (initial offsets below)."
    )


def write_calibration_report(root: Path | str, params: mdl.TwinParams) -> pd.DataFrame:
    """CALIBRATION.md and calibration.png from the raw files under ``root``."""
    root = Path(root)
    view = pipeline_view(root)
    targets = published_targets()
    residuals = target_residuals(view.observables(), targets)
    table = _comparison(view.kb)
    metrics, selected = heldout_results(view)
    _figure(table, residuals, root / "calibration.png")
    rows = "\n".join(
        f"| {r.run} | {r.measurement} | {r.time_min:.1f} | {r.n_targets} | {r.k_um_per_m:.2f} | {r.k_paper:.1f} | "
        f"{r.dk:+.2f} | {r.b_um:.2f} | {r.b_paper:.1f} | {r.db:+.2f} | {r.r2:.3f} | {r.rms_um:.3f} |"
        for r in table.itertuples()
    )
    rises, rise_note = _rise_table(view)
    miss_run, miss_meas, miss_dir, miss_pos = faults.MISSING_READING
    text = f"""\
# Calibration of the twin against the paper's published fits and tables

**SIMULATED data.** Every figure below is computed by `python -m thermaxis.twin generate`
(and `calibrate`) from the RAW files of this folder -- faults included -- with the
pipeline's own library and default configuration (`config/config.yaml`): cleaning and
window-mean temperatures (`thermaxis.cleaning.run.clean_and_assemble_run`), pass-mean errors
({miss_run} M{miss_meas:02d} has no `{miss_dir}` capture at {miss_pos:g} mm: the pipeline keeps the other pass's reading there),
and the least-squares line of each measurement, k in um/m and b in um at 185 mm
(`thermaxis.method.decouple.decouple_table`, the paper's Eq. 6).

## Targets

The calibration objective is the sum of squares of every target's residuals divided by
its tolerance (weight = 1 / tolerance), plus weak priors. Its targets are the paper's
published fits and tables only; the pipeline's held-out results (below) are outcomes.

| target | weight (tolerance) | acceptance | achieved RMS, all 32 measurements | worst run | met |
|---|---|---|---|---|---|
{_target_rows(residuals, targets)}

Eq. 8 is printed for 185, 205, 225 and 445 mm only (the other rows are elided in the
paper); its tolerance is the paper's Table 7 error RMSE, as the issue asks; the
paper's own point-by-point prediction error (Table 4) is 1.6 um. Where targets compete
the objective weights them tighter than their acceptance (`thermaxis.twin.fit.OBJECTIVE_FACTOR`):
weighted at the acceptance bounds, Eq. 8 and Eq. 9 pull Table 5's intercepts to an RMS
of 0.36-0.40 um, and Table 5 then pushes Eq. 9's b just past its bound. The achieved values are measured on the
raw files (with noise and faults); the fit itself sees the noise-free model.

Per run, RMS of each target's residuals:

| run | Table 5 k | Table 5 b | Eq. 9 k | Eq. 9 b | Eq. 8 |
|---|---|---|---|---|---|
{_per_run_rows(residuals)}

**Table 1** (workshop air; met by the air profiles of `thermaxis.twin.conditions`, not
fitted): range of the cleaned ambient sensor `{view.config['ambient_sensor']}` over each log.

| run | Table 1 degC | twin degC | largest miss degC | within 0.2 degC |
|---|---|---|---|---|
{_ambient_rows(view)}

**Fig. 10 and the text on temperature rises.** The paper's text says only that the
temperatures of experiments 2-4 follow the trends of Fig. 10 (experiment 1) except the
ambient one, and that the ambient falls in experiments 3 and 4 (cooling switched on).
Fig. 10's curves are not in the text available to us, so no number was transcribed
from it and no rise enters the objective; the rises of the twin (last minus first
measurement, degC) are shown for comparison with the figure:

{rises}

{rise_note}

![twin vs paper](calibration.png)

## What the published statements imply together

{_first_measurement_floor(targets)}

{_table4_tension(residuals, targets, view.config['paper_fold'])}

## Held-out results of the pipeline (fold {view.config['paper_fold']}, default configuration)

Computed here with the workflow's own selection and models
(`thermaxis.method.folds.select_for_fold`, `evaluate_configuration`; the same numbers as
`snakemake results/twin/tables/metrics.csv`). RMSE / max |residual| / MAE:

| model | target | paper table | paper | new twin | previous twin (Table 5 only) |
|---|---|---|---|---|---|
{_heldout_rows(metrics)}

Sensitive points the default configuration selects on the training runs: k {selected['k']};
b {selected['b']}; point-by-point common set {selected['pointwise']} (previous twin: k
{PREVIOUS_TWIN_SELECTION['k']}; b {PREVIOUS_TWIN_SELECTION['b']}; point-by-point {PREVIOUS_TWIN_SELECTION['pointwise']}; the paper: k T1, T6, T12; b T2, T7, T11;
point-by-point T1, T11, T12). {_conclusions(metrics)}

## Per measurement

time: start of the measurement, minutes from the start of M1.

| run | meas | time min | targets | k twin | k paper | dk | b twin | b paper | db | R^2 | resid RMS um |
|---|---|---|---|---|---|---|---|---|---|---|---|
{rows}

Linearity of the error curves (as in the paper, strongly but not perfectly linear):
R^2 of the line {table['r2'].min():.3f} ... {table['r2'].max():.3f} (median {table['r2'].median():.3f}),
residual RMS {table['rms_um'].min():.3f} ... {table['rms_um'].max():.3f} um (median {table['rms_um'].median():.3f} um).

## How the parameters were fitted

`python -m thermaxis.twin calibrate` (`make twin-calibrate`) refits the free parameters
with `scipy.optimize.least_squares` (trust region, deterministic start at the priors'
centres) on the NOISE-FREE model -- pass mean with the reversal error, sensor
temperatures averaged over each measurement's readings, without noise -- against the
targets above. It writes `src/thermaxis/twin_params.json` and regenerates this folder.
The free parameters (documented in `thermaxis.twin.model`): five heat-input
coefficients, the screw's expansion gain and the interferometer's
material-normalisation gain, the geometric slope, five drift gains, six
effective-capacity factors, the mountings and calibration offsets of the six sensors
the paper's Eq. 8 and Eq. 9 use, and per run {len(mdl.INITIAL_PARAMETERS)} initial temperature offsets (a
machine is rarely at equilibrium when a test starts). The workshop-air profiles, the
network's conductances, the other sensors and the instrument constants are fixed and
documented in the code.

{_parameter_tables(params)}
"""
    (root / "CALIBRATION.md").write_text(text, encoding="utf-8")
    return table
