"""Does compensating help? The deployment verdict from the held-out runs.

Each held-out run was compensated by the model of its own fold, which never saw it
(:func:`thermaxis.compensation.held_out.held_out_tables`). The verdict rests on the paired
change of each run (compensated minus uncompensated) of its largest |deviation| over the
stroke and both directions, and of E of ISO 230-2, each the worst over its measurements:

- a run is *improved* when a quantity shrinks by more than the tolerance and none grows
  by more; *worsened* when one grows by more; *unchanged* otherwise. The tolerance is
  what the measurement resolves (:func:`tolerance_um`), from the config, never from a run.
  A run is *untested* when the controller's fallback withheld the compensation at every
  one of its measurements (a temperature outside its fold's training range, a sensor
  fault): nothing was applied, so it says nothing of the model;
- **recommended** when more than half the runs improve with confidence (the one-sided
  sign test of "at most half improve", p <= significance) and the median change of the
  largest |deviation| is a reduction; the runs it worsens are the edge of the conditions
  it was tested on;
- **not recommended** when the runs say it harms: at least as many worsened as improved
  (unchanged runs set aside, as the sign test does), or the median change is an increase;
- **not established** otherwise: the runs lean to improvement but are too few, or no run
  tested it; the verdict says how many more improving runs would pass the test.

A compensation that is not recommended is still written, and says so. The rule and its
sources: docs/recommendation.md.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from thermaxis.labels import natural_key

__all__ = [
    "QUANTITIES",
    "OUTCOMES",
    "tolerance_um",
    "sign_test_p",
    "clopper_pearson",
    "median_interval",
    "runs_needed",
    "run_changes",
    "withheld_throughout",
    "deployment_verdict",
    "verdict_sentence",
]

# (name in the verdict, column before, column after) of the held-out summary table
QUANTITIES = (
    ("largest_abs", "largest_abs_uncompensated_um", "largest_abs_compensated_um"),
    ("E", "E_uncompensated_um", "E_compensated_um"),
)
OUTCOMES = ("recommended", "not_established", "not_recommended")


def tolerance_um(stroke_mm: float, accuracy_ppm: float, floor_um: float) -> float:
    """The per-run change the measurement resolves: the instrument's stated linear accuracy
    over the measured stroke, and never below ``floor_um``. 1 ppm of 1 mm is 1e-3 um."""
    return max(float(floor_um), float(accuracy_ppm) * float(stroke_mm) * 1e-3)


def sign_test_p(n: int, improved: int) -> float:
    """One-sided p of "at most half the runs improve": P(X >= improved), X ~ Binomial(n, 1/2).
    An unchanged run counts as not improved."""
    # Exact integers: the division is the only rounding, at any n.
    return sum(math.comb(n, i) for i in range(max(improved, 0), n + 1)) / 2**n


def clopper_pearson(n: int, k: int, alpha: float) -> tuple[float, float]:
    """The exact interval of a share k/n: each end a one-sided 1 - alpha bound (two-sided
    1 - 2 alpha), so the lower end exceeds 1/2 exactly when the sign test passes at alpha."""
    from scipy.stats import beta

    lower = 0.0 if k == 0 else float(beta.ppf(alpha, k, n - k + 1))
    upper = 1.0 if k == n else float(beta.ppf(1.0 - alpha, k + 1, n - k))
    return lower, upper


def median_interval(values, alpha: float) -> tuple[float, float, float]:
    """The distribution-free interval of a median from order statistics: (x_(j), x_(n-j+1))
    with the largest j whose one-sided miss P(Binomial(n, 1/2) <= j - 1) is at most alpha;
    with too few values, the full range. Returns (low, high, its two-sided coverage)."""
    x = np.sort(np.asarray(values, dtype=float))
    n = x.size
    j = 1
    while j < (n + 1) // 2 and 1.0 - sign_test_p(n, j + 1) <= alpha:
        j += 1
    coverage = 1.0 - 2.0 * (1.0 - sign_test_p(n, j))
    return float(x[j - 1]), float(x[n - j]), max(coverage, 0.0)


def runs_needed(n: int, improved: int, alpha: float) -> int:
    """The fewest further runs, all improving, after which the sign test passes at alpha."""
    m = 0
    while sign_test_p(n + m, improved + m) > alpha:
        m += 1
    return m


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
    for name, before, after in _available(summary):
        worst_before = grouped[before].max().loc[runs].to_numpy(dtype=float)
        worst_after = grouped[after].max().loc[runs].to_numpy(dtype=float)
        columns[f"{name}_before_um"] = worst_before
        columns[f"{name}_after_um"] = worst_after
        columns[f"{name}_change_um"] = worst_after - worst_before
    return pd.DataFrame(columns)


def withheld_throughout(summary: pd.DataFrame, runs) -> list[bool]:
    """Per run of ``runs``: did the fallback withhold the compensation at every measurement?

    Withheld means a fallback status (not ``ok``) and nothing applied: every quantity the
    same compensated as uncompensated. A run held from its first cycle applies zero
    parameters, and adding zero is exact, so the equality is exact too; a run holding an
    earlier good value applies it and is judged on its changes. A summary without a
    ``status`` column (no fallback policy) withholds nothing.
    """
    if "status" not in summary.columns:
        return [False] * len(runs)
    withheld = summary["status"].ne("ok")
    for _, before, after in _available(summary):
        same = summary[after].eq(summary[before]) | (summary[after].isna() & summary[before].isna())
        withheld &= same
    by_run = withheld.groupby(summary["run"], sort=False).all()
    return [bool(by_run.loc[run]) for run in runs]


def _effects(
    changes: pd.DataFrame, names: list[str], tolerance: float, withheld: list[bool]
) -> list[str]:
    """Each run untested (``withheld``), or improved, unchanged or worsened beyond
    ``tolerance`` over every quantity."""
    values = changes[[f"{name}_change_um" for name in names]].to_numpy(dtype=float)
    worse = (values > tolerance).any(axis=1)
    better = (values < -tolerance).any(axis=1) & ~worse
    return [
        "untested" if h else "worsened" if w else "improved" if b else "unchanged"
        for h, w, b in zip(withheld, worse, better, strict=True)
    ]


def _quantity(changes: pd.DataFrame, name: str, alpha: float) -> dict:
    """One quantity's median change with its interval, and its worst run, over the runs
    that give it (E needs a span of readings)."""
    given = changes[np.isfinite(changes[f"{name}_change_um"].to_numpy(dtype=float))]
    change = given[f"{name}_change_um"].to_numpy(dtype=float)
    low, high, coverage = median_interval(change, alpha)
    worst = int(change.argmax())
    before = float(given[f"{name}_before_um"].iloc[worst])
    return {
        "median_change_um": float(np.median(change)),
        "median_interval_um": [low, high],
        "median_interval_coverage": coverage,
        "worst_run": str(given["run"].iloc[worst]),
        "worst_change_um": float(change[worst]),
        "worst_share_of_uncompensated": float(change[worst] / before) if before > 0 else None,
    }


def _outcome(
    improved: int, worsened: int, tested: int, p: float, median_change: float, alpha: float
) -> str:
    # No run it acted on says nothing either way: absence of evidence, not of an effect.
    if tested == 0:
        return "not_established"
    # Harm is what the runs that changed say: as many worsened as improved (the sign test's
    # own view, which sets unchanged runs aside), or a median increase. Establishing a
    # benefit is stricter: there an unchanged or untested run counts against it
    # (sign_test_p), as the controller applies nothing there either.
    if worsened >= improved or median_change > 0:
        return "not_recommended"
    if p <= alpha and median_change < 0:
        return "recommended"
    return "not_established"


def deployment_verdict(summary: pd.DataFrame, tolerance: float, significance: float) -> dict:
    """The verdict ``model.json`` carries, from the held-out summary table (one row per
    measurement), the per-run ``tolerance`` [um] and the sign test's ``significance``.

    Returns a JSON-ready dict: the counts of improved, unchanged and worsened runs (and
    their names), the share improved with its interval and the sign test's p, per quantity
    the median change with its interval and the worst run, the per-run values, the
    ``outcome`` (one of :data:`OUTCOMES`), ``runs_needed`` when not established, and
    ``recommended_for_deployment``.
    """
    if summary.empty:
        raise ValueError(
            "no held-out measurements: the deployment verdict needs at least one held-out run"
        )
    changes = run_changes(summary)
    names = [name for name, _, _ in _available(summary)]
    effects = _effects(changes, names, tolerance, withheld_throughout(summary, changes["run"]))
    n, improved = len(changes), effects.count("improved")
    p = sign_test_p(n, improved)
    low, high = clopper_pearson(n, improved, significance)
    verdict: dict = {
        "held_out_runs": n,
        "tolerance_um": float(tolerance),
        "significance": float(significance),
        "improved_runs": improved,
        "unchanged_runs": effects.count("unchanged"),
        "worsened_runs": effects.count("worsened"),
        "worsened": [r for r, e in zip(changes["run"], effects, strict=True) if e == "worsened"],
        "untested_runs": effects.count("untested"),
        "untested": [r for r, e in zip(changes["run"], effects, strict=True) if e == "untested"],
        "share_improved": improved / n,
        "share_interval": [low, high],
        "sign_test_p": p,
    }
    for name in names:
        verdict[name] = _quantity(changes, name, significance)
    outcome = _outcome(
        improved,
        verdict["worsened_runs"],
        n - verdict["untested_runs"],
        p,
        verdict["largest_abs"]["median_change_um"],
        significance,
    )
    verdict["outcome"] = outcome
    verdict["runs_needed"] = (
        max(runs_needed(n, improved, significance), 1) if outcome == "not_established" else None
    )
    verdict["recommended_for_deployment"] = outcome == "recommended"
    verdict["runs"] = [
        {**{k: (str(v) if k == "run" else float(v)) for k, v in row.items()}, "effect": effect}
        for row, effect in zip(changes.to_dict("records"), effects, strict=True)
    ]
    return verdict


def _untested_clause(verdict: dict) -> str:
    """The runs the fallback withheld the compensation from throughout, when there are any."""
    untested = verdict.get("untested", [])
    if not untested:
        return ""
    verb = "does" if len(untested) == 1 else "do"
    return f", and the fallback withheld it throughout {_names(untested)}, which {verb} not test it"


def _names(runs: list[str]) -> str:
    return ", ".join(runs[:-1]) + f" and {runs[-1]}" if len(runs) > 1 else runs[0]


# The judged quantities by name; "the" goes before the largest |deviation| in running text.
_MEASURE_WORDS = {"largest_abs": "largest |deviation|", "E": "E of ISO 230-2"}


def _measure_in_text(quantity: str) -> str:
    return ("the " if quantity == "largest_abs" else "") + _MEASURE_WORDS[quantity]


def _worst_increase(verdict: dict, unit: str) -> str:
    """The largest increase among the worsened runs, in whichever quantity grew: a run is
    worsened by either, so the largest |deviation|'s own worst run may be one that improved."""
    run, name = max(
        (
            (r, q)
            for r in verdict["runs"]
            if r["effect"] == "worsened"
            for q in _MEASURE_WORDS
            if np.isfinite(r.get(f"{q}_change_um", np.nan))
        ),
        key=lambda pair: pair[0][f"{pair[1]}_change_um"],
    )
    change, before = run[f"{name}_change_um"], run[f"{name}_before_um"]
    of = f", {change / before:.0%} of its uncompensated error" if before > 0 else ""
    return f"worst {run['run']}: {_MEASURE_WORDS[name]} {change:+.2f} {unit}{of}"


def verdict_sentence(verdict: dict, unit: str = "um") -> str:
    """The verdict in a few sentences, the same words on every surface: with ``unit`` "um"
    (ASCII) for model.json and the export headers, "µm" for the index, the model reports and
    the answer line."""
    n, k, alpha = verdict["held_out_runs"], verdict["improved_runs"], verdict["significance"]
    largest = verdict["largest_abs"]
    low, high = verdict["share_interval"]
    m_low, m_high = largest["median_interval_um"]
    p = verdict["sign_test_p"]
    evidence = (
        f"of {n} held-out run(s) compensating improves {k} beyond the "
        f"+/-{verdict['tolerance_um']:.2f} {unit} the measurement resolves "
        f"({k / n:.0%}, {1 - 2 * alpha:.0%} interval {low:.0%} to {high:.0%}; sign test "
        f"p = {p:.2g} {'<=' if p <= alpha else '>'} {alpha:g}), leaves "
        f"{verdict['unchanged_runs']} unchanged and worsens {verdict['worsened_runs']}"
        f"{_untested_clause(verdict)}; "
        f"median change of the largest |deviation| {largest['median_change_um']:+.2f} {unit} "
        f"({largest['median_interval_coverage']:.0%} interval {m_low:+.2f} to "
        f"{m_high:+.2f} {unit})."
    )
    worsened = verdict["worsened"]
    worst = f" It worsens {_names(worsened)} ({_worst_increase(verdict, unit)})" if worsened else ""
    outcome = verdict["outcome"]
    if outcome == "recommended":
        edge = f"{worst}: the edge of the conditions it was tested on." if worsened else ""
        return f"Recommended for deployment: {evidence}{edge}"
    if outcome == "not_established":
        untested = verdict.get("untested_runs", 0) == n
        if untested:
            why, where = (
                "No held-out run tests it (the fallback's reasons are in "
                "compensation/summary.csv; most often temperatures outside the range its "
                "fold's model was trained on):",
                "at conditions within the ranges of the other runs",
            )
        else:
            why = "Too few runs to tell:"
            where = (
                f"at the conditions of {_names(worsened)} or outside those tested"
                if worsened
                else "at conditions outside those tested, or repeats of them"
            )
        return (
            f"Not established: {evidence}{worst + '.' if worsened else ''} {why} "
            f"{verdict['runs_needed']} more held-out run(s) that it improves would establish it, "
            f"{where}."
        )
    nothing = _no_help_clause(verdict) if k == 0 else ""
    return f"NOT recommended for deployment: {evidence}{worst + '.' if worsened else ''}{nothing}"


def _no_help_clause(verdict: dict) -> str:
    """Why a compensation that improves no run is refused. Where some run lowered one
    measure beyond the tolerance while raising the other, the temperatures did predict part
    of the drift, and the sentence says which runs and measures instead of claiming they
    predict none of it."""
    tolerance = verdict["tolerance_um"]
    mixed: dict[tuple[str, str], list[str]] = {}
    for run in verdict["runs"]:
        changes = {q: run.get(f"{q}_change_um", math.nan) for q in _MEASURE_WORDS}
        lower = [q for q, c in changes.items() if c < -tolerance]
        higher = [q for q, c in changes.items() if c > tolerance]
        if lower and higher:
            mixed.setdefault((lower[0], higher[0]), []).append(run["run"])
    if not mixed:
        return (
            " It helps no held-out run beyond the tolerance: nothing here shows that the "
            "temperatures predict this axis's drift."
        )
    parts = [
        f"it lowers {_measure_in_text(down)} of {_names(runs)} beyond the tolerance but raises "
        f"{_measure_in_text(up)} there"
        for (down, up), runs in mixed.items()
    ]
    return f" It helps no held-out run beyond the tolerance in both measures: {'; '.join(parts)}."
