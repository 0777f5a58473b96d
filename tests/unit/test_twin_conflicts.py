"""thermaxis.twin.conflicts: the cost of optimising two groups of targets together, by hand."""

from __future__ import annotations

from thermaxis.twin.conflicts import GROUPS, Experiment, conflicts_markdown, pair_costs

FIGURES = {"table6_holds": 1.0, "table3_hits": 30, "decoupled_mlr_max_abs": 1.7,
           "pointwise_mlr_max_abs": 4.2, "table5_k_rms": 0.45, "table5_b_rms": 0.28,
           "eq9_k_rms": 2.5, "eq9_b_rms": 0.5}  # fmt: skip


def test_a_pair_costs_what_each_group_loses_against_its_own_best():
    groups = list(GROUPS)
    experiments = [Experiment((), FIGURES)]
    experiments += [Experiment((g,), FIGURES) for g in groups]
    experiments += [
        Experiment((a, b), FIGURES) for i, a in enumerate(groups) for b in groups[i + 1 :]
    ]
    # Table 3 with Table 5: 30 hits alone, 26 together (4 lost); Table 5's k RMS 0.45 alone,
    # 0.40 together (better: no cost).
    experiments = [
        Experiment(e.groups, {**FIGURES, "table3_hits": 26, "table5_k_rms": 0.40})
        if e.groups == ("Table 3", "Table 5")
        else e
        for e in experiments
    ]
    costs = {(r["pair"], r["figure"]): r["cost"] for r in pair_costs(experiments)}
    assert costs[("Table 3 + Table 5", "table3_hits")] == 4
    assert costs[("Table 3 + Table 5", "table5_k_rms")] == 0
    assert costs[("held-out MLR + Eq. 9", "eq9_k_rms")] == 0
    text = conflicts_markdown(experiments)
    assert text.startswith("# Which targets the twin meets together\n\nSIMULATED")
    assert "| Table 3 + Table 5 | table3_hits | 30 | 26 | 4 |" in text
