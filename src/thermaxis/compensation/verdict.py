"""Does compensating help? The deployment verdict from the held-out runs.

Each held-out run was compensated by the model of its own fold, which never saw it
(:func:`thermaxis.compensation.heldout.held_out_tables`). A run is *improved* when its
largest |deviation| over the stroke and both directions, over all its measurements,
is smaller after compensating than before, and likewise for E of ISO 230-2; it is
*worsened* when either grows. A compensation that makes any held-out run worse by more
than ``max_worsening_um`` in either quantity is not recommended for deployment: it is
still written, and says so.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from thermaxis.labels import natural_key

__all__ = ["QUANTITIES", "run_changes", "deployment_verdict", "verdict_sentence"]

# (name in the verdict, column before, column after, words)
QUANTITIES = (
    (
        "largest_abs",
        "largest_abs_uncompensated_um",
        "largest_abs_compensated_um",
        "largest |deviation| over the stroke",
    ),
    ("E", "E_uncompensated_um", "E_compensated_um", "E of ISO 230-2"),
)


def _available(summary: pd.DataFrame) -> list[tuple]:
    """The quantities the held-out measurements give: E needs a span of readings, which a
    single-point record (one target in one direction) does not have."""
    return [q for q in QUANTITIES if summary[q[1]].notna().any()]


def run_changes(summary: pd.DataFrame) -> pd.DataFrame:
    """Per held-out run: each available quantity's worst value over its measurements, before
    and after."""
    grouped = summary.groupby("run", sort=False)
    runs = sorted(grouped.groups, key=natural_key)
    columns = {"run": runs}
    for name, before, after, _ in _available(summary):
        worst_before = grouped[before].max().loc[runs].to_numpy(dtype=float)
        worst_after = grouped[after].max().loc[runs].to_numpy(dtype=float)
        columns[f"{name}_before_um"] = worst_before
        columns[f"{name}_after_um"] = worst_after
        columns[f"{name}_change_um"] = worst_after - worst_before
    return pd.DataFrame(columns)


def deployment_verdict(summary: pd.DataFrame, max_worsening_um: float) -> dict:
    """The verdict ``model.json`` carries, from the held-out summary table (one row per measurement).

    Returns a JSON-ready dict: the number of held-out runs; per quantity how many runs
    improve and worsen, the median reduction and the worst increase; the per-run
    values; ``recommended_for_deployment`` and the reasons when it is false.
    """
    if summary.empty:
        raise ValueError(
            "no held-out measurements: the deployment verdict needs at least one held-out run"
        )
    changes = run_changes(summary)
    verdict: dict = {"held_out_runs": len(changes), "max_worsening_um": float(max_worsening_um)}
    for name, _, _, _ in _available(summary):
        change = changes[f"{name}_change_um"].to_numpy()
        verdict[name] = {
            "improved_runs": int((change < 0).sum()),
            "worsened_runs": int((change > 0).sum()),
            "median_reduction_um": float(-np.median(change)),
            "worst_increase_um": float(max(change.max(), 0.0)),
        }
    verdict["runs"] = [
        {k: (str(v) if k == "run" else float(v)) for k, v in row.items()}
        for row in changes.to_dict("records")
    ]
    # ASCII "um": model.json's words go into the controller exports' headers.
    reasons = _reasons(verdict, "um")
    verdict["recommended_for_deployment"] = not reasons
    verdict["reasons"] = reasons
    return verdict


def _reasons(verdict: dict, unit: str) -> list[str]:
    """Every held-out run and quantity that compensating worsens by more than
    ``max_worsening_um``, in words, quantity by quantity."""
    limit = verdict["max_worsening_um"]
    reasons = []
    for name, _, _, words in QUANTITIES:
        for run in verdict["runs"]:
            increase = run.get(f"{name}_change_um")
            if increase is not None and increase > limit:
                reasons.append(
                    f"held-out run {run['run']}: {words} {run[f'{name}_before_um']:.2f} -> "
                    f"{run[f'{name}_after_um']:.2f} {unit} (+{increase:.2f} {unit}, more than "
                    f"compensation.max_worsening_um = {limit:g} {unit})"
                )
    return reasons


def verdict_sentence(verdict: dict, unit: str = "um") -> str:
    """The verdict in one or two sentences: with ``unit`` "um" (ASCII) for model.json and the
    export headers, "µm" for the index and the model reports."""
    n = verdict["held_out_runs"]
    largest = verdict["largest_abs"]
    text = (
        f"On {n} held-out run(s) compensating improves {largest['improved_runs']} and worsens "
        f"{largest['worsened_runs']} (largest |deviation| over the stroke; median reduction "
        f"{largest['median_reduction_um']:.2f} {unit}, worst increase "
        f"{largest['worst_increase_um']:.2f} {unit})."
    )
    if verdict["recommended_for_deployment"]:
        return text + " Recommended for deployment."
    return text + " NOT recommended for deployment: " + "; ".join(_reasons(verdict, unit)) + "."
