"""The result blocks of the README and the guides (thermaxis.reports.docblocks): made from a
results tree, never typed; a guide that quotes a result results/ does not give fails.
The committed blocks against a real results tree: test_make_results.py (its `make results`
runs FL_THERMAL's benchmark)."""

from __future__ import annotations

import re

import pandas as pd
import pytest

from helpers import GUIDES, REPO
from thermaxis.reports.docblocks import KINDS, blocks_of, main, rewrite


def _comparison(results):
    folder = results / "_benchmarks" / "rec"
    folder.mkdir(parents=True)
    pd.DataFrame({"channel": ["ch1", "ch2"], "mae_um": [1.0, 4.5], "inputs": ["a", "b"],
                  "ridge_alpha": [10.0, 100.0], "best_published": ["GRU", "GRU"],
                  "best_published_mae_um": [3.0, 4.0], "below_best_published": [True, False],
                  "published_mae_um: GRU": [3.0, 4.0]}).to_csv(folder / "comparison.csv", index=False)  # fmt: skip


def test_a_block_is_made_again_whole_and_the_text_around_it_kept(tmp_path):
    (tmp_path / "twin" / "tables").mkdir(parents=True)
    pd.DataFrame({"target": ["a"], "published": ["1"], "reproduced": ["2"], "tolerance": ["+-1"],
                  "holds": ["yes"]}).to_csv(tmp_path / "twin" / "tables" / "faithfulness.csv", index=False)  # fmt: skip
    text = "head\n<!-- results:begin faithfulness twin -->\n| a | 1 | 9 |\n<!-- results:end -->\ntail\n"
    made = rewrite(text, tmp_path)
    assert made.startswith("head\n<!-- results:begin faithfulness twin -->\n| target |")
    assert "| a | 1 | 2 | +-1 | yes |\n<!-- results:end -->\ntail\n" in made


def test_the_benchmark_sentence_by_hand(tmp_path):
    _comparison(tmp_path)
    text = "<!-- results:begin benchmark-line rec -->\n<!-- results:end -->"
    # ch1 1.0 < 3.0; ch2 4.5 - 4.0 = 0.50 above.
    assert rewrite(text, tmp_path) == (
        "<!-- results:begin benchmark-line rec -->\nthermaxis's test MAE is 1.00 / 4.50 µm on "
        "ch1, ch2, against 3.00 / 4.00 µm for the best published model: below it on 1 of 2 "
        "channels; on ch2 it is 0.50 µm above the GRU.\n<!-- results:end -->"
    )


def test_check_lists_the_stale_blocks_and_writing_makes_them_fresh(tmp_path, capsys):
    _comparison(tmp_path)
    guide = tmp_path / "guide.md"
    guide.write_text("x\n<!-- results:begin benchmark rec -->\nold 3.38 µm\n<!-- results:end -->\n")
    assert main(["--check", "--results", str(tmp_path), str(guide)]) == 1
    assert f"stale: {guide}: results block benchmark rec" in capsys.readouterr().err
    assert main(["--results", str(tmp_path), str(guide)]) == 0
    assert (
        "old 3.38" not in guide.read_text() and "| ch2 | 4.5 | 4 | b | 100 |" in guide.read_text()
    )
    assert main(["--check", "--results", str(tmp_path), str(guide)]) == 0


def test_a_missing_result_or_an_unknown_block_is_one_line_and_nothing_is_written(tmp_path, capsys):
    guide = tmp_path / "guide.md"
    text = "<!-- results:begin answers nowhere -->\nold\n<!-- results:end -->\n"
    guide.write_text(text)
    assert main(["--results", str(tmp_path), str(guide)]) == 1
    err = capsys.readouterr().err.strip()
    assert err == (
        f"thermaxis error: {tmp_path / 'nowhere' / 'compensation' / 'model.json'}: missing; "
        "the guides' result blocks are made from it (make results)"
    )
    assert guide.read_text() == text
    guide.write_text("<!-- results:begin tally twin -->\n<!-- results:end -->\n")
    assert main(["--results", str(tmp_path), str(guide)]) == 1
    assert "unknown results block 'tally'" in capsys.readouterr().err


@pytest.mark.parametrize("path", GUIDES, ids=lambda p: p.name)
def test_every_block_of_the_guides_is_a_known_kind_with_its_names(path):
    for kind, names, _ in blocks_of(path.read_text(encoding="utf-8")):
        assert kind in KINDS and names, (path.name, kind, names)


def test_the_readme_quotes_no_result_outside_its_blocks():
    """A figure in µm in the README is a dataset's result: it must come from results/."""
    text = (REPO / "README.md").read_text(encoding="utf-8")
    outside = re.sub(r"<!-- results:begin .*?<!-- results:end -->", "", text, flags=re.S)
    assert not re.findall(r"\d+\.\d+\s*µm", outside)
    assert {kind for kind, _, _ in blocks_of(text)} == {"answers", "benchmark-line"}
