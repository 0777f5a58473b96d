"""The workflow's configuration: safe-loaded, validated, defaults filled, and its settings.

The workflow validates its config once, while Snakemake parses it, with
:func:`validate_config` (``thermaxis.pipeline.preflight``), and its rules read the
dict that returns; the library, the sweep and the tests apply the same schema
(``thermaxis/schemas/config.schema.yaml``), so they see exactly the configuration the
workflow sees.

The settings model: one frozen dataclass per stage (cleaning, decoupling, selection,
models, compensation, figures, reports, sweep), each built from its own config section
by ``from_section`` and all of them at once by :meth:`Settings.from_config`. Every
default lives in the schema: a dataclass field has none, so a value the config leaves
out comes from :func:`validate_config` or nowhere. This module imports neither
scikit-learn nor pandas: the workflow builds settings while it parses the Snakefile.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from functools import cache
from pathlib import Path

from thermaxis.errors import first_schema_error, schema_message, schema_where
from thermaxis.schemas import load_schema, load_trusted_yaml, schema_path
from thermaxis.sweep_grid import SweepGrid
from thermaxis.vocabulary import SEARCHABLE

__all__ = [
    "CONFIG_SCHEMA",
    "load_config",
    "validate_config",
    "merge",
    "fill_defaults",
    "schema_default",
    "dataset_of",
    "TemperatureCleaning",
    "ErrorCleaning",
    "CleaningSettings",
    "DecouplingSettings",
    "SelectionSettings",
    "ModelSettings",
    "FallbackSettings",
    "CompensationSettings",
    "ExtraCandidate",
    "RecommendSettings",
    "selection_overrides",
    "FigureSettings",
    "ReportSettings",
    "SweepSettings",
    "StatisticsSettings",
    "Settings",
]

CONFIG_SCHEMA = schema_path("config")


def merge(base: dict, update: dict) -> dict:
    """Recursive update, as Snakemake merges several --configfile files."""
    out = copy.deepcopy(base)
    for key, value in update.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def fill_defaults(instance: dict, schema: dict) -> None:
    """Fill the schema's defaults into ``instance`` in place, into nested objects and lists of objects."""
    for key, sub in schema.get("properties", {}).items():
        if "default" in sub and key not in instance:
            instance[key] = copy.deepcopy(sub["default"])
        value = instance.get(key)
        if isinstance(value, dict) and sub.get("type") == "object":
            fill_defaults(value, sub)
        elif isinstance(value, list) and sub.get("items", {}).get("type") == "object":
            for item in value:
                if isinstance(item, dict):
                    fill_defaults(item, sub["items"])


@cache
def _schema_defaults() -> dict:
    defaults: dict = {}
    fill_defaults(defaults, load_schema("config"))
    return defaults


def schema_default(*keys: str):
    """The config schema's default at ``keys`` (e.g. ``"models", "gpr_max_samples"``), read once.

    For code that takes a setting without a config, such as an estimator's keyword
    parameters, so that its default is the schema's rather than a second copy.
    """
    value = _schema_defaults()
    for key in keys:
        value = value[key]
    return copy.deepcopy(value)


def validate_config(config: dict, schema_path=CONFIG_SCHEMA) -> dict:
    """Return a validated copy with defaults filled; raise ValueError with one line otherwise."""
    with open(schema_path, encoding="utf-8") as fh:
        schema = load_trusted_yaml(fh)
    filled = copy.deepcopy(config)
    fill_defaults(filled, schema)
    error = first_schema_error(schema, filled)
    if error is not None:
        raise ValueError(f"config {schema_where(error)}: {schema_message(error)}")
    filled["dataset"] = dataset_of(filled)
    return filled


def dataset_of(config: dict) -> str:
    """The dataset folder of one run: ``dataset`` if given, else the first of ``datasets``."""
    return config.get("dataset") or config["datasets"][0]


def load_config(*paths, overrides: dict | None = None) -> dict:
    """Safe-load one or more YAML files (later ones win), apply overrides, validate."""
    config: dict = {}
    # Relative to the working folder, as Snakemake reads `configfile:`.
    for path in paths or (Path("config/config.yaml"),):
        with open(path, encoding="utf-8") as fh:
            doc = load_trusted_yaml(fh) or {}
        if not isinstance(doc, dict):
            raise ValueError(f"{path}: expected a mapping at top level")
        config = merge(config, doc)
    if overrides:
        config = merge(config, overrides)
    return validate_config(config)


# --------------------------------------------------------------------------- settings


def _pair(values) -> tuple[float, float]:
    return float(values[0]), float(values[1])


def _sensor_lists(fixed: Mapping) -> tuple:
    """``{target: [sensor, ...]}`` as ``((target, (sensor, ...)), ...)``, sorted by target (hashable)."""
    return tuple(sorted((target, tuple(sensors)) for target, sensors in (fixed or {}).items()))


def _svr_grid(grid: Mapping) -> tuple:
    return tuple((name, tuple(grid[name])) for name in ("C", "epsilon", "gamma"))


def _searchable(algorithms) -> tuple[str, ...]:
    wrong = [a for a in algorithms if a not in SEARCHABLE]
    if wrong:
        raise ValueError(
            f"config models.searched: {wrong[0]!r} has no strength to search; expected some of {', '.join(SEARCHABLE)}"
        )
    return tuple(algorithms)


def _grid(grid: Mapping) -> tuple:
    """A search grid as a frozen, ordered tuple: ((parameter, (value, ...)), ...)."""
    return tuple((name, tuple(values)) for name, values in sorted(grid.items()))


@dataclass(frozen=True)
class TemperatureCleaning:
    """Settings of :func:`thermaxis.cleaning.temperatures.clean_temperatures` (config ``temperatures``).

    With ``estimate_clock_offsets`` every source but ``reference_source`` (None: the
    source with most sensors) gets the offset
    :func:`thermaxis.cleaning.clock.estimate_clock_offset` finds *after* its given offset is
    applied, added to it; ``max_offset_s`` bounds the search and ``offset_step_s`` is
    its lag step (refined below one step). The schema enforces every range and choice.
    """

    interval_s: float
    spike_threshold: float
    spike_min_deviation_c: float
    spike_max_rate_c_per_min: float
    spike_window_s: float  # a spike's samples span at most this, and the trend resumes after
    excursions: str  # keep | fault: a longer departure is kept (reported) or dropped as a fault
    limits_c: tuple[float, float]
    max_gap_s: float
    estimate_clock_offsets: bool
    reference_source: str | None
    max_offset_s: float
    offset_step_s: float

    def __post_init__(self):
        # JSON Schema cannot compare two items of one array.
        low, high = self.limits_c
        if not low < high:
            raise ValueError(f"limits_c must be (low, high) with low < high, got {self.limits_c}")


@dataclass(frozen=True)
class ErrorCleaning:
    """Settings of :func:`thermaxis.cleaning.passes.combine_passes`.

    direction : "mean" (mean of the forward and backward readings), "+" or "-".
    max_missing_fraction : more targets than this fraction without a reading is an error.
    """

    direction: str
    max_missing_fraction: float


@dataclass(frozen=True)
class DisplacementQC:
    """Settings of :func:`thermaxis.cleaning.displacement.displacement_findings` (config ``errors``).

    outliers : "warn" keeps a single-reading outlier, "drop" removes the reading.
    steps : "warn" keeps the run as it is, "refuse" stops with the step named.
    threshold : departures must exceed this many noise sigmas ...
    min_deviation_um : ... and this many µm to be flagged.
    """

    outliers: str
    steps: str
    threshold: float
    min_deviation_um: float


@dataclass(frozen=True)
class CleaningSettings:
    """Cleaning of one run (config ``temperatures`` and ``errors``) and its plausibility checks."""

    temperatures: TemperatureCleaning
    errors: ErrorCleaning
    allow_long_gaps: bool  # a long gap during a measurement is a warning, not an error
    window: str  # temperature of a measurement: "mean" over its window or value at its "start"
    plausible_median_c: tuple[float, float]
    max_abs_error_um: float
    displacement: DisplacementQC

    @classmethod
    def from_sections(cls, temperatures: Mapping, errors: Mapping) -> CleaningSettings:
        t, e = temperatures, errors
        return cls(
            temperatures=TemperatureCleaning(
                interval_s=float(t["interval_s"]),
                spike_threshold=float(t["spike_threshold"]),
                spike_min_deviation_c=float(t["spike_min_deviation_c"]),
                spike_max_rate_c_per_min=float(t["spike_max_rate_c_per_min"]),
                spike_window_s=float(t["spike_window_s"]),
                excursions=t["excursions"],
                limits_c=_pair(t["limits_c"]),
                max_gap_s=float(t["max_gap_s"]),
                estimate_clock_offsets=bool(t["estimate_clock_offsets"]),
                reference_source=t["reference_source"] or None,
                max_offset_s=float(t["max_offset_s"]),
                offset_step_s=float(t["offset_step_s"]),
            ),
            errors=ErrorCleaning(
                direction=e["direction"], max_missing_fraction=float(e["max_missing_fraction"])
            ),
            allow_long_gaps=bool(t["allow_long_gaps"]),
            window=t["window"],
            plausible_median_c=_pair(t["plausible_median_c"]),
            max_abs_error_um=float(e["max_abs_error_um"]),
            displacement=DisplacementQC(
                outliers=e["outliers"],
                steps=e["steps"],
                threshold=float(e["qc_threshold"]),
                min_deviation_um=float(e["qc_min_deviation_um"]),
            ),
        )


@dataclass(frozen=True)
class DecouplingSettings:
    degree: int  # of the polynomial each error curve is decoupled into; 1 is the paper's line

    @classmethod
    def from_section(cls, decoupling: Mapping) -> DecouplingSettings:
        return cls(degree=int(decoupling["degree"]))


@dataclass(frozen=True)
class SelectionSettings:
    method: str  # fuzzy_grey | correlation | all | fixed
    scope: str  # training | all
    n_clusters: int
    similarity: str
    grade: str
    rho: float
    normalisation: str
    pointwise_common: int
    fixed: tuple  # ((target, (sensor, ...)), ...) for method "fixed"

    @classmethod
    def from_section(cls, selection: Mapping) -> SelectionSettings:
        s = selection
        return cls(
            method=s["method"],
            scope=s["scope"],
            n_clusters=int(s["n_clusters"]),
            similarity=s["similarity"],
            grade=s["grade"],
            rho=float(s["rho"]),
            normalisation=s["normalisation"],
            pointwise_common=int(s["pointwise_common"]),
            fixed=_sensor_lists(s["fixed"]),
        )

    def fixed_for(self, target: str) -> tuple[str, ...]:
        mapping = dict(self.fixed)
        if target not in mapping:
            raise ValueError(
                f"config selection.fixed: no sensor list for {target!r} (method 'fixed' needs k, b and pointwise)"
            )
        return tuple(mapping[target])


def selection_overrides(selection: SelectionSettings, overrides: Mapping) -> SelectionSettings:
    """``selection`` with some of its config keys changed (a recommendation candidate's)."""
    known = {f.name for f in fields(SelectionSettings)}
    unknown = sorted(set(overrides) - known)
    if unknown:
        raise ValueError(
            f"config recommend.extra_candidates: unknown selection setting {unknown[0]!r}"
        )
    values = {k: (_sensor_lists(v) if k == "fixed" else v) for k, v in overrides.items()}
    return replace(selection, **values)


@dataclass(frozen=True)
class ModelSettings:
    algorithms: tuple[str, ...]
    ridge_alpha: float
    lasso_alpha: float
    pls_components: int
    svr_kernel: str
    svr_grid: tuple  # ((parameter, (value, ...)), ...): C, epsilon, gamma
    searched: tuple[str, ...]  # ridge, lasso, pls whose strength an inner search chooses
    search_grids: tuple  # ((algorithm, ((parameter, (value, ...)), ...)), ...)
    inner_search: tuple[int, int]  # (max_loco_runs, group_folds)
    gpr_max_samples: int
    svr_max_samples: int
    svr_search_folds: int
    svr_max_loco_runs: int
    interval_level: float
    random_state: int
    signals: tuple[str, ...]  # operating signals added to every model's inputs

    @classmethod
    def from_section(cls, models: Mapping) -> ModelSettings:
        m = models
        return cls(
            algorithms=tuple(m["algorithms"]),
            ridge_alpha=float(m["ridge_alpha"]),
            lasso_alpha=float(m["lasso_alpha"]),
            pls_components=int(m["pls_components"]),
            svr_kernel=m["svr_kernel"],
            svr_grid=_svr_grid(m["svr_grid"]),
            searched=_searchable(m["searched"]),
            search_grids=tuple(
                (name, _grid(grid)) for name, grid in sorted(m["search_grids"].items())
            ),
            inner_search=(
                int(m["inner_search"]["max_loco_runs"]),
                int(m["inner_search"]["group_folds"]),
            ),
            gpr_max_samples=int(m["gpr_max_samples"]),
            svr_max_samples=int(m["svr_max_samples"]),
            svr_search_folds=int(m["inner_search"]["svr_folds"]),
            svr_max_loco_runs=int(m["inner_search"]["svr_max_loco_runs"]),
            interval_level=float(m["interval_level"]),
            random_state=int(m["random_state"]),
            signals=tuple(m["signals"]),
        )

    def params_for(self, algorithm: str) -> dict | None:
        if algorithm == "ridge":
            return {"alpha": self.ridge_alpha}
        if algorithm == "lasso":
            return {"alpha": self.lasso_alpha}
        if algorithm == "pls":
            return {"n_components": self.pls_components}
        if algorithm == "svr":
            return {"kernel": self.svr_kernel}
        return None

    def grid(self) -> dict:
        return {name: list(values) for name, values in self.svr_grid}

    def search_grid_for(self, algorithm: str) -> dict | None:
        """The inner search's grid of ``algorithm`` when it is searched, else None (fixed)."""
        if algorithm not in self.searched:
            return None
        return {name: list(values) for name, values in dict(self.search_grids)[algorithm]}


@dataclass(frozen=True)
class FallbackSettings:
    """When the compensation must not trust its inputs, and what it does then.

    A fault is any used sensor that is missing (NaN) or stale (older than
    ``max_sensor_age_s``), outside ``plausible_c``, changing faster than
    ``max_rate_c_per_min`` since the previous sample, or (as the model's input,
    absolute or relative) more than ``range_margin_c`` outside the training range.
    ``policy`` "hold" keeps the last good K0 and tan(beta); "ramp_to_zero" scales the
    last good values linearly down to zero over ``ramp_to_zero_min`` minutes. Before any
    good sample the compensation is zero. Values return as soon as a sample is good.
    """

    range_margin_c: float
    plausible_c: tuple[float, float]
    max_rate_c_per_min: float
    max_sensor_age_s: float
    policy: str
    ramp_to_zero_min: float


@dataclass(frozen=True)
class CompensationSettings:
    """Which model is deployed, the configured approach and algorithm (``model: paper``; a
    single-position dataset uses pointwise), what the verdict's tolerance and test rest on
    and the fallback."""

    model: str  # recommended | paper | a candidate's name
    accuracy_ppm: float
    tolerance_floor_um: float
    significance: float
    approach: str
    algorithm: str
    fallback: FallbackSettings

    @classmethod
    def from_section(cls, compensation: Mapping) -> CompensationSettings:
        c = compensation
        return cls(
            model=c["model"],
            accuracy_ppm=float(c["accuracy_ppm"]),
            tolerance_floor_um=float(c["tolerance_floor_um"]),
            significance=float(c["significance"]),
            approach=c["approach"],
            algorithm=c["algorithm"],
            fallback=FallbackSettings(
                range_margin_c=float(c["range_margin_c"]),
                plausible_c=_pair(c["plausible_c"]),
                max_rate_c_per_min=float(c["max_rate_c_per_min"]),
                max_sensor_age_s=float(c["max_sensor_age_s"]),
                policy=c["fallback"],
                ramp_to_zero_min=float(c["ramp_to_zero_min"]),
            ),
        )


@dataclass(frozen=True)
class ExtraCandidate:
    """A user's candidate of the recommendation: selection settings that differ, and its inputs."""

    name: str
    approach: str
    algorithm: str
    selection: tuple  # ((key, value), ...) overriding the configured selection
    time_inputs: bool
    signals: bool


# The recommendation's kernel candidate and the kernel algorithms: none may join the
# combination (config recommend.combine).
KERNEL_CANDIDATE = "pointwise-svr"
KERNEL_ALGORITHMS = ("svr", "gpr")


@dataclass(frozen=True)
class RecommendSettings:
    combine: tuple[str, ...]  # the super learner's members: linear candidates
    weighting: str  # a key of thermaxis.method.nested.WEIGHTINGS
    lags_min: tuple[float, ...]
    baseline_lags_min: tuple[float, ...]
    max_loco_runs: int  # of the outer loop; the inner one always leaves one run out
    group_folds: int
    kernel_max_runs: int
    extra_candidates: tuple[ExtraCandidate, ...]

    @classmethod
    def from_section(cls, recommend: Mapping) -> RecommendSettings:
        r = recommend
        extra = tuple(
            ExtraCandidate(
                name=e["name"],
                approach=e["approach"],
                algorithm=e["algorithm"],
                selection=tuple(sorted(e["selection"].items())),
                time_inputs=bool(e["time_inputs"]),
                signals=bool(e["signals"]),
            )
            for e in r["extra_candidates"]
        )
        # A kernel model's expansion cannot join one affine block (model.json).
        kernels = {KERNEL_CANDIDATE} | {e.name for e in extra if e.algorithm in KERNEL_ALGORITHMS}
        for name in r["combine"]:
            if name in kernels:
                raise ValueError(
                    f"config recommend.combine: {name!r} is a kernel candidate; the combination "
                    "is one linear model, expected linear candidates (paper, evidence-ridge, ...)"
                )
        return cls(
            combine=tuple(r["combine"]),
            weighting=r["weighting"],
            lags_min=tuple(float(v) for v in r["lags_min"]),
            baseline_lags_min=tuple(float(v) for v in r["baseline_lags_min"]),
            max_loco_runs=int(r["max_loco_runs"]),
            group_folds=int(r["group_folds"]),
            kernel_max_runs=int(r["kernel_max_runs"]),
            extra_candidates=extra,
        )

    @property
    def all_lags_min(self) -> tuple[float, ...]:
        """Every lag time constant a candidate may see: what the clean rule computes."""
        return tuple(sorted({*self.lags_min, *self.baseline_lags_min}))


@dataclass(frozen=True)
class FigureSettings:
    formats: tuple[str, ...]
    dpi: int
    run: str  # run of the single-run figures; empty = the first run
    algorithms: tuple[str, ...]  # whose held-out predictions get figures

    @classmethod
    def from_section(cls, figures: Mapping) -> FigureSettings:
        f = figures
        return cls(
            formats=tuple(f["formats"]),
            dpi=int(f["dpi"]),
            run=f["run"],
            algorithms=tuple(f["algorithms"]),
        )


@dataclass(frozen=True)
class ReportSettings:
    model_algorithms: tuple[str, ...]  # algorithms the model report of each fold shows side by side
    combined_above_runs: int  # more runs than this: one report of all conditions

    @classmethod
    def from_section(cls, reports: Mapping) -> ReportSettings:
        return cls(
            model_algorithms=tuple(reports["model_algorithms"]),
            combined_above_runs=int(reports["combined_above_runs"]),
        )


@dataclass(frozen=True)
class SweepSettings:
    grid: SweepGrid
    svr_grid: tuple  # as ModelSettings.svr_grid, with "models" already resolved
    folds: tuple[str, ...]  # empty = every run
    batches: int
    cluster_batch_size: int
    seconds_per_evaluation: float

    @classmethod
    def from_section(cls, sweep: Mapping, models: ModelSettings) -> SweepSettings:
        """``models`` supplies the SVR grid when ``sweep.svr_grid`` is ``"models"``."""
        s = sweep
        return cls(
            grid=SweepGrid(
                methods=tuple(s["methods"]),
                n_clusters=tuple(int(n) for n in s["n_clusters"]),
                similarities=tuple(s["similarity"]),
                grades=tuple(s["grade"]),
                approaches=tuple(s["approaches"]),
                degrees=tuple(int(d) for d in s["degrees"]),
                algorithms=tuple(s["algorithms"]),
                fixed=_sensor_lists(s["fixed"]),
                max_subsets=int(s["max_subsets"]),
            ),
            svr_grid=models.svr_grid if s["svr_grid"] == "models" else _svr_grid(s["svr_grid"]),
            folds=tuple(s["folds"]),
            batches=int(s["batches"]),
            cluster_batch_size=int(s["cluster_batch_size"]),
            seconds_per_evaluation=float(s["seconds_per_evaluation"]),
        )

    def models(self, base: ModelSettings) -> ModelSettings:
        """``base`` with the sweep's SVR grid: the models the sweep evaluates."""
        return replace(base, svr_grid=self.svr_grid)


@dataclass(frozen=True)
class StatisticsSettings:
    """Config ``statistics``: the confidence level, bootstrap size, seed and block length."""

    level: float
    n_resamples: int
    seed: int
    block_length: int  # measurements per block; 0: round(n^(1/3)) per fold
    stability_subsets: tuple[int, int]  # (max_loco_runs, group_folds)

    @classmethod
    def from_section(cls, section) -> StatisticsSettings:
        subsets = section["stability_subsets"]
        return cls(
            level=float(section["level"]),
            n_resamples=int(section["n_resamples"]),
            seed=int(section["seed"]),
            block_length=int(section["block_length"]),
            stability_subsets=(int(subsets["max_loco_runs"]), int(subsets["group_folds"])),
        )

    @property
    def alpha(self) -> float:
        return 1.0 - self.level


@dataclass(frozen=True)
class Settings:
    """Every stage's settings, parsed once from one configuration."""

    cleaning: CleaningSettings
    decoupling: DecouplingSettings
    selection: SelectionSettings
    models: ModelSettings
    compensation: CompensationSettings
    recommend: RecommendSettings
    figures: FigureSettings
    reports: ReportSettings
    sweep: SweepSettings
    statistics: StatisticsSettings

    @classmethod
    def from_config(cls, config: Mapping) -> Settings:
        """The settings of ``config``, validated and with the schema's defaults filled first."""
        return cls.from_validated(validate_config(dict(config)))

    @classmethod
    def from_validated(cls, c: Mapping) -> Settings:
        """The settings of a config that :func:`validate_config` returned (not validated again)."""
        models = ModelSettings.from_section(c["models"])
        return cls(
            cleaning=CleaningSettings.from_sections(c["temperatures"], c["errors"]),
            decoupling=DecouplingSettings.from_section(c["decoupling"]),
            selection=SelectionSettings.from_section(c["selection"]),
            models=models,
            compensation=CompensationSettings.from_section(c["compensation"]),
            recommend=RecommendSettings.from_section(c["recommend"]),
            figures=FigureSettings.from_section(c["figures"]),
            reports=ReportSettings.from_section(c["reports"]),
            sweep=SweepSettings.from_section(c["sweep"], models),
            statistics=StatisticsSettings.from_section(c["statistics"]),
        )
