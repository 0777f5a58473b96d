"""Figure captions, display names and the natural order of labels, kept free of matplotlib.

The workflow builds every caption when it is parsed (for Snakemake's report), so this
module must import in milliseconds; :mod:`thermaxis.figures` re-exports it.
"""

from __future__ import annotations

import string

__all__ = [
    "DISPLAY_NAMES",
    "OTHER_SIMULATED_NOTE",
    "SIMULATED_NOTE",
    "figure_caption",
    "provenance_note",
]


# What a simulated dataset's figures are stamped with and their captions end with: the
# twin names what it stands in for; any other simulated dataset only what it is not.
SIMULATED_NOTE = "Simulated data (thermal twin), not the paper's measurements."
OTHER_SIMULATED_NOTE = "Simulated data, not measurements of a machine."


def provenance_note(simulated: bool, twin: bool = True) -> str | None:
    """The note of a dataset's figures: :data:`SIMULATED_NOTE` for the twin (a simulated
    dataset that reproduces the paper), :data:`OTHER_SIMULATED_NOTE` for any other
    simulated one, None for measured data."""
    if not simulated:
        return None
    return SIMULATED_NOTE if twin else OTHER_SIMULATED_NOTE


# How the model labels of the tables (thermaxis.method.estimators) read in legends and captions;
# unknown labels are shown as they are.
DISPLAY_NAMES = {
    "mlr": "MLR", "svr": "SVR", "gpr": "GPR", "pls": "PLS", "ridge": "ridge", "lasso": "lasso",
    "bayesridge": "evidence ridge",
    "decoupled": "decoupled", "pointwise": "point-by-point",
}  # fmt: skip


def _display(label) -> str:
    return DISPLAY_NAMES.get(str(label), str(label))


# --------------------------------------------------------------------------- captions

# figure id (thermaxis.figures.registry) -> (the paper's figure, caption body with {detail}
# placeholders). The paper repeats Figs. 14/15 for SVR as Figs. 16/17; one drawing serves both.
_CAPTIONS: dict[str, tuple[str | None, str]] = {
    "fig2_positioning_error": (
        "2",
        "Positioning error of the axis in the first measurement of run {run}, before the axis warms up "
        "(forward and backward passes combined).",
    ),
    "fig3_ambient": (
        "3",
        "Ambient temperature of every run against the time since the run's first measurement.",
    ),
    "fig5_unzeroed": (
        "5",
        "Unzeroed thermal positioning error of run {run}: one curve per measurement, labelled by the time "
        "since the first measurement; the interferometer is zeroed only before the first measurement.",
    ),
    "fig6_error_vs_time": (
        "6",
        "Unzeroed thermal positioning error of run {run} at every target position against the time since "
        "the first measurement.",
    ),
    "fig7_error_surface": (
        "7",
        "Unzeroed thermal positioning error of run {run} over position and time.",
    ),
    "fig8_rezeroed": (
        "8",
        "Re-zeroed thermal positioning error of run {run}: each measurement minus its own reading at the "
        "first position, which hides the drift between measurements and leaves the expansion along the stroke.",
    ),
    "fig9_other_runs": (
        "9",
        "Unzeroed thermal positioning error of runs {runs}, one panel per run, one curve per measurement.",
    ),
    "fig10_temperature_rise": (
        "10",
        "Temperature rise of the sensors of run {run} relative to their values at the start of the first "
        "measurement.",
    ),
    "fig12_slope_intercept": (
        "12",
        "Slope k (top) and intercept b (bottom) of the decoupled error line of every measurement, one line per run.",
    ),
    "kb_prediction": (
        "14/16",
        "Measured and predicted slope k and intercept b of the held-out run(s) of fold {fold} "
        "({approach} approach, {algorithm}).",
    ),
    "error_prediction": (
        "15/17",
        "Measured (solid) and predicted (dashed) thermal positioning error of the held-out run(s) of fold "
        "{fold} ({approach} approach, {algorithm}) and the residuals (measured minus predicted).",
    ),
    "fold_comparison": (
        None,
        "Prediction accuracy of every fold (held-out run), approach and algorithm: RMSE (top) "
        "and maximum absolute residual (bottom) of the {target}, with the confidence interval of "
        "a block bootstrap of the held-out measurements (config statistics.level).",
    ),
    "selection_stability": (
        None,
        "Stability of the sensitive points: for each fold (column) and target, the share of the "
        "leave-one-run-out subsets of the fold's training runs whose selection chooses each sensor "
        "(row); ringed cells are the sensors the fold itself chose (Table 6 for k and b).",
    ),
    "recommendation": (
        None,
        "Held-out error of each fold (run): RMSE (top) and maximum absolute residual (bottom) of the "
        "model a nested leave-one-condition-out choice picks without that run, beside the paper's "
        "configuration on the same run.",
    ),
    "compensation_drift": (
        None,
        "Thermal drift of held-out run {fold} (after ISO 230-3's drift plots): the largest absolute deviation "
        "over the stroke and both directions at each measurement, with the static pitch table of the "
        "first measurement only and with the temperature compensation of the fold's model as the "
        "controller applies it (exported K0, tan(beta), P0 after the fallback policy). Ringed points "
        "are measurements where the policy held or ramped the values.",
    ),
}
# The point-by-point error prediction is the paper's Fig. 11 (it has no approach to name).
_VARIANTS: dict[tuple[str, str], tuple[str | None, str]] = {
    ("error_prediction", "pointwise"): (
        "11",
        "Point-by-point prediction ({algorithm}) of the held-out run(s) of fold {fold}: measured (solid) and "
        "predicted (dashed) errors of every measurement, and the residuals (measured minus predicted).",
    ),
}


_TARGET_NAMES = {"k": "slope k", "b": "intercept b", "error": "thermal positioning error"}


def _detail_text(key: str, value) -> str:
    if key == "target":
        return _TARGET_NAMES.get(str(value), str(value))
    if isinstance(value, (list, tuple)):
        return ", ".join(_display(v) for v in value)
    return _display(value)


def figure_caption(
    figure_id: str, dataset_name: str, simulated: bool, twin: bool = True, **details
) -> str:
    """One English caption for a figure of the pipeline.

    Parameters
    ----------
    figure_id : str
        A figure id of :mod:`thermaxis.figures.registry`: ``"fig2_positioning_error"`` ...
        ``"fig12_slope_intercept"`` (the paper's Figs. 4 and 13 are photographs/schematics),
        ``"kb_prediction"``, ``"error_prediction"`` (point by point: the paper's Fig. 11),
        ``"fold_comparison"`` or ``"compensation_drift"``.
    dataset_name : str
        Name of the dataset the figure was drawn from.
    simulated : bool
        Whether the dataset is simulated; if so the caption ends with its
        :func:`provenance_note`.
    twin : bool
        Whether a simulated dataset is the thermal twin (it reproduces the paper).
    **details
        Exactly the placeholders the caption needs, e.g. ``run="E1"``, ``runs=["E2", "E3"]``,
        ``fold``, ``approach``, ``algorithm``, ``target``.

    Returns
    -------
    str
    """
    if figure_id not in _CAPTIONS:
        raise ValueError(f"unknown figure id {figure_id!r}; expected one of {', '.join(_CAPTIONS)}")
    if not isinstance(dataset_name, str) or not dataset_name:
        raise ValueError(f"dataset_name must be a non-empty string, got {dataset_name!r}")
    variant = (figure_id, details.get("approach"))
    if variant in _VARIANTS:
        paper_figure, body = _VARIANTS[variant]
        details = {k: v for k, v in details.items() if k != "approach"}
    else:
        paper_figure, body = _CAPTIONS[figure_id]
    needed = {field for _, field, _, _ in string.Formatter().parse(body) if field}
    missing = sorted(needed - details.keys())
    extra = sorted(details.keys() - needed)
    if missing or extra:
        raise ValueError(
            f"caption {figure_id} needs details {sorted(needed)}; missing {missing}, unexpected {extra}"
        )
    parts = [body.format(**{k: _detail_text(k, v) for k, v in details.items()})]
    if paper_figure is not None:
        parts.append(f"Counterpart of the paper's Fig. {paper_figure}.")
    parts.append(f"Dataset: {dataset_name}.")
    if simulated:
        parts.append(provenance_note(simulated, twin))
    return " ".join(parts)
