"""Cross-dataset summary on hand-made metrics tables (numbers worked out by hand)."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
import yaml

from thermaxis.errors import DataError
from thermaxis.reports import crossdataset

ASKED = ("--datasets", "twin", "fl_thermal")
HEADER = "fold,approach,algorithm,target,rmse,max_abs,mae,residual_min,residual_max\n"


def _result(results: Path, name: str, kind: str, rows: str) -> Path:
    """results/<name>/ with a metrics table and the provenance that names its dataset.yaml."""
    raw = results.parent / "raw" / name
    raw.mkdir(parents=True)
    (raw / "dataset.yaml").write_text(yaml.safe_dump({"name": name, "provenance": {"kind": kind}}))
    out = results / name
    (out / "tables").mkdir(parents=True)
    (out / "tables" / "metrics.csv").write_text(HEADER + rows)
    (out / "provenance.json").write_text(json.dumps({"data": {"root": str(raw)}}))
    return out


@pytest.fixture
def two_datasets(tmp_path):
    results = tmp_path / "results"
    # twin: two folds; k/b rows must not enter the error summary.
    _result(results, "twin", "simulated",
            "E1,decoupled,mlr,error,1.0,2.0,0.5,-2.0,1.0\n"
            "E2,decoupled,mlr,error,3.0,6.0,1.5,-6.0,1.0\n"
            "E1,decoupled,mlr,k,9.0,90.0,9.0,-9.0,9.0\n"
            "E1,pointwise,svr,error,2.0,4.0,1.0,-4.0,1.0\n"
            "E2,pointwise,svr,error,4.0,5.0,1.0,-5.0,1.0\n")  # fmt: skip
    # A measured single-position dataset: point-by-point only, three folds.
    _result(results, "fl_thermal", "measured",
            "R1,pointwise,mlr,error,0.3,0.6,0.2,-0.6,0.1\n"
            "R2,pointwise,mlr,error,0.6,0.9,0.2,-0.9,0.1\n"
            "R3,pointwise,mlr,error,0.9,1.5,0.2,-1.5,0.1\n")  # fmt: skip
    (results / "bench").mkdir()  # not a dataset
    return results


def test_summary_means_and_worst_over_folds_by_hand(two_datasets):
    assert crossdataset.main(["--results", str(two_datasets), *ASKED, "--formats", "png"]) == 0
    out = two_datasets / "_datasets"
    table = pd.read_csv(out / "summary.csv")
    assert list(table.columns) == list(crossdataset.SUMMARY_COLUMNS)
    rows = {(r.dataset, r.approach, r.algorithm): r for r in table.itertuples()}
    assert sorted(rows) == [
        ("fl_thermal", "pointwise", "mlr"),
        ("twin", "decoupled", "mlr"),
        ("twin", "pointwise", "svr"),
    ]
    twin_mlr = rows["twin", "decoupled", "mlr"]
    # (1 + 3) / 2 = 2; (2 + 6) / 2 = 4; worst 6; the k row (90) is left out.
    assert (
        twin_mlr.n_folds,
        twin_mlr.mean_rmse_um,
        twin_mlr.mean_max_abs_um,
        twin_mlr.worst_max_abs_um,
    ) == (2, 2.0, 4.0, 6.0)
    assert twin_mlr.data == "simulated"
    fl = rows["fl_thermal", "pointwise", "mlr"]
    # (0.3 + 0.6 + 0.9) / 3 = 0.6; (0.6 + 0.9 + 1.5) / 3 = 1.0; worst 1.5.
    assert (fl.n_folds, fl.data) == (3, "measured")
    assert fl.mean_rmse_um == pytest.approx(0.6) and fl.mean_max_abs_um == pytest.approx(1.0)
    assert fl.worst_max_abs_um == 1.5
    assert (
        rows["twin", "pointwise", "svr"].mean_max_abs_um,
        rows["twin", "pointwise", "svr"].worst_max_abs_um,
    ) == (4.5, 5.0)
    markdown = (out / "summary.md").read_text()
    assert "SIMULATED data: twin" in markdown and "fl_thermal" in markdown
    assert (out / "heldout_error.png").stat().st_size > 0
    assert not list(out.glob(".*"))  # no temporary file left behind


def test_outputs_are_byte_identical_on_a_rerun(two_datasets, tmp_path):
    crossdataset.main(["--results", str(two_datasets), *ASKED, "--out", str(tmp_path / "a")])
    crossdataset.main(["--results", str(two_datasets), *ASKED, "--out", str(tmp_path / "b")])
    for name in ("summary.csv", "summary.md", "heldout_error.png", "heldout_error.pdf"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


def test_a_bad_metrics_cell_leaves_its_dataset_out_with_one_line_naming_file_line_and_column(
    two_datasets, capsys
):
    path = two_datasets / "twin" / "tables" / "metrics.csv"
    path.write_text(HEADER + "E1,decoupled,mlr,error,1.0,n/a,0.5,-2.0,1.0\n")
    assert crossdataset.main(["--results", str(two_datasets), *ASKED]) == 0
    warning = capsys.readouterr().err.splitlines()[0]
    assert warning == (
        f"thermaxis warning: {two_datasets / 'twin'} left out of the cross-dataset summary: "
        f"{path}: line 2, column 'max_abs': expected a number, got 'n/a'"
    )
    summary = pd.read_csv(two_datasets / "_datasets" / "summary.csv")
    assert summary["dataset"].unique().tolist() == ["fl_thermal"]


def test_every_dataset_under_results_is_read_unless_named(two_datasets, capsys):
    # A third dataset built by another command (thermaxis run of one dataset) is listed too.
    _result(two_datasets, "extra", "measured", "R1,pointwise,mlr,error,2.0,3.0,1,-3,1\n")
    # A user's own dataset, run for one target: metrics but no provenance yet.
    mine = _result(two_datasets, "mine", "measured", "R1,pointwise,mlr,error,5.0,9.0,1,-9,1\n")
    (mine / "provenance.json").unlink()
    (two_datasets / "_benchmarks" / "fl_thermal").mkdir(parents=True)  # not a dataset
    assert crossdataset.main(["--results", str(two_datasets)]) == 0
    assert "mine" not in capsys.readouterr().err
    summary = pd.read_csv(two_datasets / "_datasets" / "summary.csv")
    assert sorted(summary["dataset"].unique()) == ["extra", "fl_thermal", "twin"]
    page = (two_datasets / "index.html").read_text()
    assert ">extra<" in page and "mine" not in page and "_benchmarks" not in page
    # Named, only those are read.
    assert crossdataset.main(["--results", str(two_datasets), *ASKED]) == 0
    summary = pd.read_csv(two_datasets / "_datasets" / "summary.csv")
    assert sorted(summary["dataset"].unique()) == ["fl_thermal", "twin"]
    # Asked for, it is left out with a warning naming its folder and what is missing.
    capsys.readouterr()
    assert crossdataset.main(["--results", str(two_datasets), *ASKED, "mine"]) == 0
    err = capsys.readouterr().err
    assert (
        f"thermaxis warning: {mine} left out of the cross-dataset summary: {mine}/provenance.json"
        in err
    )
    # Nothing readable at all is an error, and nothing is written.
    out = two_datasets.parent / "none"
    assert (
        crossdataset.main(["--results", str(two_datasets), "--out", str(out), "--datasets", "mine"])
        == 1
    )
    assert "no dataset results could be read" in capsys.readouterr().err and not out.exists()


def test_missing_column_and_missing_provenance_are_named(two_datasets):
    path = two_datasets / "twin" / "tables" / "metrics.csv"
    path.write_text("fold,approach,algorithm,target,rmse\nE1,decoupled,mlr,error,1.0\n")
    with pytest.raises(DataError, match="column 'max_abs' missing"):
        crossdataset.read_metrics(path)
    (two_datasets / "fl_thermal" / "provenance.json").unlink()
    with pytest.raises(
        DataError, match="fl_thermal/provenance.json: expected the workflow's provenance"
    ):
        crossdataset.dataset_kind(two_datasets / "fl_thermal")


def _summary(datasets: dict[str, list[str]], algorithms: list[str]) -> pd.DataFrame:
    rows = [
        {"dataset": name, "data": "measured", "approach": approach, "algorithm": algorithm,
         "mean_max_abs_um": 3.0, "worst_max_abs_um": 5.0}
        for name, approaches in datasets.items()
        for approach in approaches
        for algorithm in algorithms
    ]  # fmt: skip
    return pd.DataFrame(rows)


@pytest.mark.parametrize(
    "datasets",
    [
        {"fl_thermal": ["pointwise"]},  # five long labels in a row overran the figure
        {"fl_thermal": ["pointwise"], "twin": ["decoupled", "pointwise"]},
        {"a_long_dataset_name": ["pointwise"], "b": ["pointwise"], "c": ["decoupled"]},
    ],
)
def test_the_figure_is_drawn_whole_inside_its_canvas(datasets):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from thermaxis.figures import registry

    summary = _summary(datasets, ["mlr", "svr", "ridge", "pls", "gpr"])
    fig = registry.function(crossdataset.FIGURE.draw)(summary)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()  # the layout, as saving the figure makes it
    drawn = fig.get_tightbbox(canvas.get_renderer())  # inches, every label and the legend
    pixel = 1 / fig.dpi
    assert drawn.x0 >= -pixel and drawn.y0 >= -pixel, drawn
    assert drawn.x1 <= fig.get_figwidth() + pixel and drawn.y1 <= fig.get_figheight() + pixel, drawn
    assert len(fig.legends[0].get_texts()) == len(
        summary.drop_duplicates(["approach", "algorithm"])
    )
