"""thermaxis.pipeline.runner: each warning text reaches the terminal once; the log keeps all."""

from __future__ import annotations

import logging

from thermaxis.pipeline.runner import _configure_logging


def test_a_repeated_warning_is_printed_once_and_logged_every_time(tmp_path, capsys):
    log = tmp_path / "job.log"
    logger = _configure_logging(str(log))
    for _ in range(3):
        logger.warning("fold E4: hold on 2 of 9 cycles")
        # A Python warning, as logging.captureWarnings hands it over.
        logging.getLogger("py.warnings").warning(
            "x.py:3: UserWarning: no lambda-cut gives 6 classes"
        )
    logger.warning("another text")
    for handler in logging.getLogger("thermaxis").handlers:
        handler.flush()
    err = capsys.readouterr().err.splitlines()
    assert err == [
        "thermaxis warning: fold E4: hold on 2 of 9 cycles",
        "thermaxis warning: no lambda-cut gives 6 classes",
        "thermaxis warning: another text",
    ]
    text = log.read_text()
    assert text.count("hold on 2 of 9 cycles") == 3 and text.count("lambda-cut") == 3
