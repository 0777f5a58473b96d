"""A family of figures drawn in worker processes: the same files as in one process."""

import pandas as pd

from thermaxis.figures.family import draw_family, family_workers


def test_workers_come_with_sixty_four_figures_each_up_to_the_cores():
    # 12 runs' 72 prediction figures: one process; 43 runs' 258: two.
    assert [family_workers(2, n) for n in (1, 72, 127, 128, 258)] == [1, 1, 1, 2, 2]
    assert family_workers(1, 300) == 1
    assert family_workers(16, 258) == 4


def _specs(tmp_path, folder):
    rows = [
        {"fold": fold, "target": target, "sensor": f"T{s}", "chosen": s == 1, "n_subsets": 3,
         "times_chosen": 3 - s % 3, "frequency": (3 - s % 3) / 3}
        for fold in ("R1", "R2") for target in ("k", "b", "pointwise") for s in range(1, 5)
    ]  # fmt: skip
    table = tmp_path / "stability.csv"
    pd.DataFrame(rows).to_csv(table, index=False)
    return [
        {"draw": "figures.statistics.fig_selection_stability", "tables": {"stability": str(table)},
         "arguments": {}, "paths": [str(tmp_path / folder / f"s{i}.png"), str(tmp_path / folder / f"s{i}.pdf")]}
        for i in range(3)
    ]  # fmt: skip


def test_two_workers_write_the_bytes_one_process_writes(tmp_path):
    draw_family(_specs(tmp_path, "one"), "SIMULATED", 100, workers=1)
    draw_family(_specs(tmp_path, "two"), "SIMULATED", 100, workers=2)
    for name in ("s0.png", "s1.pdf", "s2.png"):
        assert (tmp_path / "one" / name).read_bytes() == (tmp_path / "two" / name).read_bytes()
