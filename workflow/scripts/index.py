"""results/<dataset>/index.html: the answer first, then figures, tables, reports and
provenance; and provenance.json (code, configuration, raw-data manifest, software, run time)."""

import json
import os

from thermaxis.pipeline.runner import run_script, write_texts
from thermaxis.reports.answer import answer_of, answer_sentence
from thermaxis.reports.crossdataset import model_ranking
from thermaxis.reports.index import (
    FigureGroup,
    Headline,
    IndexFigure,
    IndexRow,
    IndexSection,
    PageTable,
    claims_table,
    deployment_comparison,
    render_index,
)
from thermaxis.reports.provenance import collect, to_json
from thermaxis.tables import read_table


def main(snakemake):
    p = snakemake.params
    here = os.path.dirname(snakemake.output.index)
    # The git state was taken when the workflow was parsed (it is a param, so a new
    # commit reruns this rule); taking it again here could disagree with that param.
    provenance = to_json(collect(p.repo, json.loads(p.config_json), p.dataset, git=p.git))

    def rel(path):
        return os.path.relpath(path, here).replace(os.sep, "/")

    sections = [
        IndexSection(
            title=title,
            intro=intro,
            rows=tuple(
                IndexRow(label, tuple((text, rel(path)) for text, path in links))
                for label, links in rows
            ),
        )
        for title, intro, rows in p.sections
    ]
    # The sweep is optional and slow: linked when it was run, never a dependency.
    if os.path.isfile(p.sweep):
        sweep = IndexRow(
            "sweep report",
            (("html", rel(p.sweep)),),
            "present when the index was built (`make sweep`)",
        )
        sections.insert(1, IndexSection(title="Sweep", rows=(sweep,)))
    figures = [
        FigureGroup(
            title,
            tuple(
                IndexFigure(
                    stem, caption, rel(thumb) if thumb else "", tuple((e, rel(f)) for e, f in links)
                )
                for stem, caption, thumb, links in entries
            ),
        )
        for title, entries in p.figures
    ]
    tables = [
        PageTable(title, read_table(path, comment="#"), rel(path), note)
        for title, path, note in p.tables
    ]
    page = render_index(
        p.dataset_name,
        p.statement,
        p.simulated,
        _headline(p.answer, rel(p.answer["figure"]["path"]), p.answer["figure"]["caption"]),
        figures,
        tables,
        sections,
        json.loads(provenance),
        subtitle=p.headline,
    )
    write_texts({snakemake.output.provenance: provenance, snakemake.output.index: page})


def _headline(answer, figure: str, caption: str) -> Headline:
    with open(answer["markdown"], encoding="utf-8") as fh:
        recommendation = fh.read().split("\n\n")[2]
    with open(answer["model"], encoding="utf-8") as fh:
        model = json.load(fh)
    claims = None
    if os.path.isfile(answer["claims"]):
        claims = claims_table(read_table(answer["claims"]), answer["claims"])
    folds = read_table(answer["recommendation"])
    return Headline(
        answer=answer_sentence(answer_of(folds, model)),
        ranking=model_ranking(read_table(answer["metrics"])),
        recommendation=recommendation,
        deployment=model["deployment"],
        comparison=deployment_comparison(folds),
        claims=claims,
        figure=figure,
        figure_caption=caption,
    )


run_script(main, snakemake)
