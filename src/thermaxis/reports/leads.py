"""The sentences each report opens with: the answer, written from the workflow's tables.

Two to four sentences per report, numbers rounded for reading; the tables further down
carry the full values. Pure functions of DataFrames, so the notebooks stay thin and the
words are tested against numbers worked out by hand.
"""

from __future__ import annotations

import html
from collections.abc import Sequence

import pandas as pd

from thermaxis.figures.captions import DISPLAY_NAMES
from thermaxis.labels import sort_naturally

__all__ = [
    "model_name",
    "how_much_more",
    "lead_html",
    "model_lead",
    "condition_lead",
    "conditions_lead",
    "dataset_lead",
    "paper_lead",
]


def model_name(approach: str, algorithm: str) -> str:
    """'the decoupled MLR': the words a lead sentence names a model with."""
    return f"{DISPLAY_NAMES.get(approach, approach)} {DISPLAY_NAMES.get(algorithm, algorithm)}"


def how_much_more(larger: float, smaller: float) -> str:
    """'twice', '3.1 times' or 'about as large as' the other value."""
    if smaller <= 0:
        return "more than"
    ratio = larger / smaller
    if ratio < 1.1:
        return "about as large as"
    if abs(ratio - 2.0) < 0.15:
        return "twice"
    return f"{ratio:.1f} times"


def lead_html(sentences: str) -> str:
    """The lead paragraph under a report's banner (escaped: it names runs and sensors)."""
    return f'<p class="tx-lead">{html.escape(sentences)}</p>'


def model_lead(
    metrics: pd.DataFrame,
    fold: str,
    models: Sequence[Sequence[str]],
    compensation: pd.DataFrame,
    compensating: tuple[str, str],
) -> str:
    """A model report's opening: the held-out run's largest errors, then what compensating did.

    ``metrics`` is the metrics table (thermaxis.pipeline.paths.METRICS), ``compensation`` the fold's compensation summary
    (one row per measurement), ``compensating`` the (approach, algorithm) it used.
    """
    rows = metrics[(metrics["fold"] == fold) & (metrics["target"] == "error")]
    shown = [
        (
            approach,
            algorithm,
            rows[(rows["approach"] == approach) & (rows["algorithm"] == algorithm)],
        )
        for approach, algorithm in models
    ]
    shown = sorted(
        [
            (a, g, float(r["max_abs"].iloc[0]), float(r["rmse"].iloc[0]))
            for a, g, r in shown
            if not r.empty
        ],
        key=lambda m: (m[2], m[0], m[1]),
    )
    sentences = []
    if shown:
        best, worst = shown[0], shown[-1]
        if len(shown) == 1:
            sentences.append(
                f"On held-out run {fold} the {model_name(best[0], best[1])}'s largest error is {best[2]:.1f} µm "
                f"(RMSE {best[3]:.2f} µm)."
            )
        else:
            sentences.append(
                f"On held-out run {fold} the {model_name(worst[0], worst[1])}'s largest error is {worst[2]:.1f} µm, "
                f"{how_much_more(worst[2], best[2])} the {model_name(best[0], best[1])}'s {best[2]:.1f} µm "
                f"(RMSE {best[3]:.2f} µm)."
            )
    sentences += _compensation_sentences(compensation, fold, compensating)
    return " ".join(sentences)


def _compensation_sentences(
    compensation: pd.DataFrame, fold: str, compensating: tuple[str, str]
) -> list[str]:
    """What compensating did to the held-out run's largest deviation, and the fallbacks."""
    if compensation.empty:
        return []
    before = float(compensation["largest_abs_uncompensated_um"].max())
    after = float(compensation["largest_abs_compensated_um"].max())
    effect = (
        "better" if after < before else "worse" if after > before else "neither better nor worse"
    )
    sentences = [
        f"Compensating with the {model_name(*compensating)} takes the largest |deviation| of {fold} "
        f"from {before:.1f} µm to {after:.1f} µm: it makes {fold} {effect}."
    ]
    held = int((compensation["status"] != "ok").sum())
    if held:
        sentences.append(
            f"The fallback policy acted at {held} of {len(compensation)} measurements."
        )
    return sentences


def condition_lead(
    run: str, condition: str, errors: pd.DataFrame, temperatures: pd.DataFrame
) -> str:
    """A condition report's opening: how long the run is, how the error drifts, which sensor warms most.

    ``errors`` and ``temperatures`` are the run's rows of the assembled tables.
    """
    by_measurement = errors.groupby("measurement", sort=True)
    largest = by_measurement["error_um"].agg(lambda s: s.abs().max())
    minutes = by_measurement["time_min"].first()
    sentences = [
        f"Run {run} ({condition}): {len(largest)} measurements over {minutes.max() - minutes.min():.0f} min.",
        f"The unzeroed error's largest magnitude goes from {largest.iloc[0]:.1f} µm at the first measurement "
        f"to {largest.iloc[-1]:.1f} µm at the last (at most {largest.max():.1f} µm).",
    ]
    if not temperatures.empty:
        rise = sort_naturally(
            temperatures.groupby("sensor", sort=True)["relative_c"].max().reset_index(), ["sensor"]
        )
        top = rise.sort_values("relative_c", ascending=False, kind="stable").iloc[0]
        sentences.append(
            f"Sensor {top['sensor']} warms most, {top['relative_c']:.1f} °C above the first measurement."
        )
    return " ".join(sentences)


def conditions_lead(largest: pd.DataFrame) -> str:
    """The combined conditions report's opening, from the largest |unzeroed error| of each measurement.

    ``largest`` holds run, measurement and largest_abs_um
    (:func:`thermaxis.figures.overview.largest_error_by_measurement`).
    """
    per_run = largest.groupby("run", sort=True)["largest_abs_um"].max()
    counts = largest.groupby("run", sort=True)["measurement"].nunique()
    top, low = per_run.idxmax(), per_run.idxmin()
    sizes = (
        f"{counts.min()} measurements each"
        if counts.min() == counts.max()
        else f"{counts.min()} to {counts.max()} measurements"
    )
    return (
        f"{len(per_run)} runs of {sizes}. The largest unzeroed error is "
        f"{per_run.max():.1f} µm, in run {top}; the run that drifts least, {low}, stays within {per_run.min():.1f} µm."
    )


def dataset_lead(summary: pd.DataFrame, repairs: pd.DataFrame, errors: pd.DataFrame) -> str:
    """A dataset report's opening: runs and measurements, what cleaning repaired, the largest error."""
    runs = len(summary)
    conditions = summary["condition"].astype(str).nunique()
    sentences = [
        f"{runs} runs under {conditions} condition(s), {int(summary['n_measurements'].sum())} measurements, "
        f"{int(summary['n_sensors'].iloc[0])} temperature sensors."
    ]
    if repairs.empty:
        sentences.append("Cleaning repaired nothing.")
    else:
        sentences.append(
            f"Cleaning repaired {int(repairs['repaired'].sum())} readings of {len(repairs)} sensor log(s); "
            "the table below says which."
        )
    at = errors.loc[errors["error_um"].abs().idxmax()]
    sentences.append(
        f"The largest unzeroed error is {abs(at['error_um']):.1f} µm, in run {at['run']} at {at['position_mm']:g} mm."
    )
    return " ".join(sentences)


def paper_lead(comparison: pd.DataFrame) -> str:
    """The paper report's opening: how many published numbers were reproduced and how closely."""
    numbers = comparison[comparison["published"].notna()]
    reproduced = numbers[numbers["reproduced"].notna()]
    worst = reproduced.assign(abs_difference=reproduced["difference"].abs()).sort_values(
        "abs_difference", ascending=False, kind="stable"
    )
    text = (
        f"{len(reproduced)} of the paper's {len(numbers)} published numbers are reproduced below."
    )
    if not worst.empty:
        top = worst.iloc[0]
        text += (
            f" The largest difference is in {top['table']} ({top['item']}): {top['reproduced']:.3g} against "
            f"{top['published']:.3g} {top['unit'] if isinstance(top['unit'], str) else ''}".rstrip()
            + "."
        )
    return text
