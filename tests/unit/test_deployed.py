"""The compensation's verdict step (thermaxis.compensation.deployed.with_verdict): the
tolerance is the instrument's accuracy over the stroke the model's positions span, worked
out by hand, and the verdict's words go with it."""

import pytest

from helpers.builders import HOLD, held_out_summary
from thermaxis.compensation.deployed import with_verdict
from thermaxis.compensation.verdict import verdict_sentence
from thermaxis.config import CompensationSettings

SETTINGS = CompensationSettings("recommended", 0.5, 0.1, 0.05, "decoupled", "mlr", HOLD)
CHOICE = {"final": {"name": "super learner"}}
# Largest |deviation| 6 um: 5.88 after compensating on R1 (-0.12 um), 5.5 on R2 to R5; E as it was.
SUMMARY = held_out_summary(
    [("R1", 1, 6.0, 5.88, 2.0, 2.0)] + [(f"R{i}", 1, 6.0, 5.5, 2.0, 2.0) for i in range(2, 6)]
)


def _deployment(positions_mm):
    fitted = {"positions_mm": positions_mm, "deployment": {"model": "recommended"}}
    return with_verdict(fitted, SUMMARY, CHOICE, SETTINGS)["deployment"]


def test_a_long_stroke_resolves_less_and_leaves_the_smaller_change_unchanged():
    # 185 to 445 mm: 260 mm x 0.5 um/m = 0.13 um, so R1's -0.12 um is within it. Four of
    # five improve: p = P(X >= 4), X ~ B(5, 1/2) = 6/32 > 0.05.
    deployment = _deployment([185.0, 305.0, 445.0])
    verdict = deployment["verdict"]
    assert verdict["tolerance_um"] == pytest.approx(0.13, abs=1e-12)
    assert (verdict["improved_runs"], verdict["unchanged_runs"]) == (4, 1)
    assert verdict["sign_test_p"] == pytest.approx(6 / 32, abs=1e-12)
    assert deployment["outcome"] == "not_established"
    assert deployment["recommended_for_deployment"] is False
    assert deployment["recommended_by_the_evidence"] == "super learner"
    assert deployment["sentence"] == verdict_sentence(verdict)


def test_a_short_stroke_falls_to_the_floor_and_every_run_improves():
    # 100 mm x 0.5 um/m = 0.05 um, below the 0.1 um floor; R1's -0.12 um is beyond it.
    # Five of five: p = 1/32 <= 0.05, and the median change (-0.5 um) is a reduction.
    deployment = _deployment([0.0, 50.0, 100.0])
    verdict = deployment["verdict"]
    assert verdict["tolerance_um"] == pytest.approx(0.1, abs=1e-12)
    assert verdict["improved_runs"] == 5
    assert verdict["sign_test_p"] == pytest.approx(1 / 32, abs=1e-12)
    assert deployment["outcome"] == "recommended"
    assert deployment["recommended_for_deployment"] is True
