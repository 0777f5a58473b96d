"""Resuming the twin's staged calibration from a file it wrote."""

from __future__ import annotations

import json

import pytest

from thermaxis.twin import stages
from thermaxis.twin.__main__ import _resume_point

NAMES = [stage.name for stage in stages.STAGES]


def test_a_resume_goes_on_at_the_stage_after_the_last_one_recorded():
    assert NAMES[stages.resume_index("kept targets with Eq. 9, pipeline")] == (
        "Table 3 restart 1, pipeline"
    )
    assert NAMES[stages.resume_index("Table 3 restart 6, pipeline")] == (
        "held-out RMSE restart 1, pipeline"
    )


def test_after_the_last_stage_only_the_polish_is_left():
    assert stages.resume_index("held-out RMSE restart 11, pipeline") == len(stages.STAGES)


@pytest.mark.parametrize("after", ["Table 6", "polish", "no such stage"])
def test_a_resume_needs_a_known_stage_followed_by_a_restart(after):
    # After "Table 6" comes a stage that does not start afresh; a polished file is finished.
    with pytest.raises(ValueError, match="cannot resume after stage"):
        stages.resume_index(after)


def test_a_file_without_a_stage_record_names_itself(tmp_path):
    path = tmp_path / "params.json"
    path.write_text(json.dumps({"global": {}, "fit": {"stages": []}}), encoding="utf-8")
    with pytest.raises(ValueError, match=r"params\.json: fit\.stages names no stage"):
        _resume_point(path)


def test_the_committed_resume_points_name_their_last_stages():
    from importlib import resources

    root = resources.files("thermaxis")
    for name, last in (
        ("twin_params.seven_stages.json", "kept targets with Eq. 9, pipeline"),
        ("twin_params.table3_restarts.json", "Table 3 restart 6, pipeline"),
        ("twin_params.heldout_restarts.json", "held-out RMSE restart 11, pipeline"),
        ("twin_params.json", "polish"),
    ):
        params, after = _resume_point(root / name)
        assert after == last and params.values


def test_resuming_a_finished_calibration_is_one_line_and_writes_nothing(tmp_path, capsys):
    from importlib import resources

    from thermaxis.twin.__main__ import main

    polished = resources.files("thermaxis") / "twin_params.json"
    written = tmp_path / "params.json"
    code = main(["calibrate", "--resume", str(polished), "--params", str(written),
                 "--out", str(tmp_path / "raw"), "--truth", str(tmp_path / "truth")])  # fmt: skip
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert "twin_params.json" in err and "the calibration is complete" in err
    assert not written.exists() and not (tmp_path / "raw").exists()
