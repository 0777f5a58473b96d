"""End-to-end: the compensation rules on tiny datasets, and what a config change reruns."""

from __future__ import annotations

import json

import pandas as pd
import yaml

from helpers.runs import LINES_RUNS
from helpers.workflow import planned_rules

TABLES = ("siemens_840d", "twincat", "residuals", "iso230_2", "summary")


def targets(name: str, runs) -> list[str]:
    out = f"results/{name}/compensation"
    return [f"{out}/{table}.csv" for table in TABLES] + [
        f"results/{name}/figures/compensation_drift_{run}.png" for run in runs
    ]


# The session's `lines_run` builds everything, the compensation outputs among them.
WANTED = targets("lines", LINES_RUNS) + ["results/lines/compensation/ThermalCompensation.st"]


def test_outputs_carry_their_conventions(lines_run):
    out = lines_run.out / "compensation"
    model = json.loads((out / "model.json").read_text())
    assert model["trained_on"] == ["R1", "R2", "R3"] and model["simulated"] is True
    assert {row["fold"] for row in model["held_out_accuracy"]} == {"R1", "R2", "R3"}
    for table in TABLES:
        text = (out / f"{table}.csv").read_text()
        assert (
            text.startswith("# thermaxis compensation") and "compensation c = -(predicted e" in text
        )
        assert "SIMULATED" in text.splitlines()[1]
    summary = pd.read_csv(out / "summary.csv", comment="#")
    assert sorted(summary["fold"].unique()) == ["R1", "R2", "R3"] and len(summary) == 15
    siemens = pd.read_csv(out / "siemens_840d.csv", comment="#")
    assert set(siemens["parameter"]) == {"SD43900", "SD43910", "SD43920"}
    # The reference state (first measurement of a run) needs no temperature compensation:
    # exactly 0 on any CPU, as each regression's change is its value at the first
    # measurement minus its value at the same inputs, both evaluated alike (not a BLAS
    # product, whose kernels may sum two equal rows differently: -4.1e-35 mm on SkylakeX).
    first = siemens[(siemens["measurement"] == 1) & (siemens["parameter"] != "SD43920")]
    assert (first["value"] == 0).all(), first["value"].tolist()
    assert "END_FUNCTION_BLOCK" in (out / "ThermalCompensation.st").read_text()


def test_model_option_reruns_compensation_and_figure_option_does_not(lines_run):
    work, config, wanted = lines_run.work, lines_run.config, WANTED
    doc = yaml.safe_load(config.read_text())
    model_change = work / "model_change.yaml"
    model_change.write_text(yaml.safe_dump({**doc, "models": {**doc["models"], "random_state": 7}}))
    rules = planned_rules(lines_run.snakemake(*wanted, "-n", "--configfile", str(model_change)))
    assert "compensation" in rules, rules

    figure_change = work / "figure_change.yaml"
    figure_change.write_text(yaml.safe_dump({**doc, "figures": {**doc["figures"], "dpi": 120}}))
    rules = planned_rules(lines_run.snakemake(*wanted, "-n", "--configfile", str(figure_change)))
    assert rules == {"fig_results"}, rules


def test_the_verdict_reads_the_same_on_every_surface(lines_run, capsys):
    """model.json's outcome and sentence, the exports' headers, the Structured Text block,
    the index's answer box and the answer line `make results` prints: one wording."""
    import html

    from thermaxis.compensation.verdict import OUTCOMES, verdict_sentence
    from thermaxis.reports import answer

    out = lines_run.out
    deployment = json.loads((out / "compensation" / "model.json").read_text())["deployment"]
    verdict = deployment["verdict"]
    assert deployment["outcome"] == verdict["outcome"] in OUTCOMES
    assert deployment["recommended_for_deployment"] is (verdict["outcome"] == "recommended")
    ascii_words, page_words = verdict_sentence(verdict), verdict_sentence(verdict, unit="µm")
    assert deployment["sentence"] == ascii_words and ascii_words.isascii()
    for table in TABLES:
        header = (out / "compensation" / f"{table}.csv").read_text().split("\n# Convention")[0]
        assert header.endswith(f"# Deployment: {ascii_words}"), (table, header)
    assert (
        f"Deployment: {ascii_words}"
        in (out / "compensation" / "ThermalCompensation.st").read_text()
    )
    assert html.escape(page_words) in (out / "index.html").read_text(encoding="utf-8")
    answer.main([str(out)])
    assert page_words in capsys.readouterr().out.splitlines()[-1]
