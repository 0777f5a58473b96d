"""Tests of the figure library: every figure on several dataset shapes, the plotted
numbers against values worked out by hand from the synthetic tables, byte-identical
output, and the captions.

The synthetic errors follow e(run r, measurement m, position x) = b_m + k_r * (x - x0) / 1000
with b_m = -0.5 (m - 1) um and k_r = -(10 + r) um/m, so every plotted value is known
in closed form.
"""

from __future__ import annotations

import warnings

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from thermaxis.figures import captions, font_subsets, style
from thermaxis.figures import paper as paper_figures
from thermaxis.figures import predictions as prediction_figures
from thermaxis.figures import statistics as statistics_figures

STEP_MIN = 20.0


def slope(r: int) -> float:
    return -(10.0 + r)


def intercept(m: int) -> float:
    return -0.5 * (m - 1)


def make_dataset(n_runs: int, positions, n_meas: int) -> dict:
    """All tables the figure functions take, for runs R1..Rn (natural order differs from string order at R10)."""
    positions = np.asarray(positions, dtype=float)
    x0 = positions[0]
    runs = [f"R{r + 1}" for r in range(n_runs)]
    err_rows, kb_rows, amb_rows = [], [], []
    for r, run in enumerate(runs):
        for m in range(1, n_meas + 1):
            t = STEP_MIN * (m - 1)
            for x in positions:
                e = intercept(m) + slope(r) * (x - x0) / 1000.0
                err_rows.append(
                    dict(
                        run=run,
                        condition=r + 1,
                        measurement=m,
                        time_min=t,
                        position_mm=x,
                        error_um=e,
                        rezeroed_um=slope(r) * (x - x0) / 1000.0,
                    )
                )
            kb_rows.append(
                dict(
                    run=run,
                    measurement=m,
                    time_min=t,
                    k_um_per_m=slope(r),
                    b_um=intercept(m),
                    r2=1.0,
                    rms_um=0.0,
                )
            )
        for e_min in np.arange(-10.0, STEP_MIN * n_meas, 5.0):
            amb_rows.append(dict(run=run, elapsed_min=e_min, temperature_c=30.0 - r + 0.01 * e_min))
    errors = pd.DataFrame(err_rows)
    kb = pd.DataFrame(kb_rows)

    kb_pred_rows, err_pred_rows, metric_rows = [], [], []
    models = [("decoupled", "mlr"), ("decoupled", "gpr"), ("pointwise", "mlr")]
    for approach, algorithm in models:
        band = algorithm == "gpr"
        for f, fold in enumerate(runs):
            for row in kb[kb["run"] == fold].itertuples():
                for target, value in (("k", row.k_um_per_m), ("b", row.b_um)):
                    kb_pred_rows.append(
                        dict(
                            fold=fold,
                            approach=approach,
                            algorithm=algorithm,
                            run=fold,
                            measurement=row.measurement,
                            time_min=row.time_min,
                            target=target,
                            measured=value,
                            predicted=value + 0.25,
                            lower=value - 0.5 if band else np.nan,
                            upper=value + 1.0 if band else np.nan,
                        )
                    )
            for row in errors[errors["run"] == fold].itertuples():
                err_pred_rows.append(
                    dict(
                        fold=fold,
                        approach=approach,
                        algorithm=algorithm,
                        run=fold,
                        measurement=row.measurement,
                        time_min=row.time_min,
                        position_mm=row.position_mm,
                        measured=row.error_um,
                        predicted=row.error_um - 0.125,
                        residual=0.125,
                        lower=row.error_um - 1.0 if band else np.nan,
                        upper=row.error_um + 1.0 if band else np.nan,
                    )
                )
            for target in ("k", "b", "error"):
                metric_rows.append(
                    dict(
                        fold=fold,
                        approach=approach,
                        algorithm=algorithm,
                        target=target,
                        rmse=0.1 * (f + 1) + (0.01 if band else 0.0),
                        max_abs=0.2 * (f + 1),
                        mae=0.05,
                        residual_min=-0.1,
                        residual_max=0.1,
                    )
                )

    elapsed = np.arange(-10.0, STEP_MIN * n_meas, 2.5)
    series = pd.DataFrame(
        {
            "time": pd.Timestamp("2022-05-10T09:00:00") + pd.to_timedelta(elapsed, unit="min"),
            "elapsed_min": elapsed,
        }
    )
    for i in range(3):
        series[f"T{i + 1}"] = 20.0 + i + 0.05 * (i + 1) * elapsed
    return dict(
        runs=runs,
        positions=positions,
        n_meas=n_meas,
        errors=errors,
        kb=kb,
        ambient=pd.DataFrame(amb_rows),
        series=series,
        kb_pred=pd.DataFrame(kb_pred_rows),
        err_pred=pd.DataFrame(err_pred_rows),
        metrics=pd.DataFrame(metric_rows),
    )


SHAPES = {
    "tiny": (2, [0.0, 10.0, 20.0, 30.0], 3),
    "one_run_three_positions_two_measurements": (1, [185.0, 315.0, 445.0], 2),
    # Also more measurements and positions than a legend holds: the colour-bar path.
    "five_runs_many_lines": (5, np.arange(185.0, 446.0, 20.0), 12),
}


@pytest.fixture(scope="module", params=list(SHAPES), ids=list(SHAPES))
def dataset(request):
    return make_dataset(*SHAPES[request.param])


@pytest.fixture(scope="module")
def tiny():
    return make_dataset(*SHAPES["tiny"])


def all_figures(d: dict) -> dict:
    first, last = d["runs"][0], d["runs"][-1]
    return {
        "fig2": lambda: paper_figures.fig2_positioning_error(d["errors"], first),
        "fig3": lambda: paper_figures.fig3_ambient(d["ambient"]),
        "fig5": lambda: paper_figures.fig5_unzeroed(d["errors"], first),
        "fig6": lambda: paper_figures.fig6_error_vs_time(d["errors"], first),
        "fig7": lambda: paper_figures.fig7_error_surface(d["errors"], first),
        "fig8": lambda: paper_figures.fig8_rezeroed(d["errors"], first),
        "fig9": lambda: paper_figures.fig9_other_runs(d["errors"], d["runs"]),
        "fig10": lambda: paper_figures.fig10_temperature_rise(d["series"]),
        "fig11": lambda: prediction_figures.fig_error_prediction(
            d["err_pred"], last, "pointwise", "mlr"
        ),
        "fig12": lambda: paper_figures.fig12_slope_intercept(d["kb"]),
        "kb_prediction": lambda: prediction_figures.fig_kb_prediction(
            d["kb_pred"], last, "decoupled", "gpr"
        ),
        "error_prediction": lambda: prediction_figures.fig_error_prediction(
            d["err_pred"], last, "decoupled", "gpr"
        ),
        "fold_comparison": lambda: prediction_figures.fig_fold_comparison(d["metrics"]),
    }


def lines_of(ax):
    """Data lines only: the zero reference lines drawn with axhline span axes coordinates."""
    return [
        line for line in ax.get_lines() if line.get_label() and not line.get_label().startswith("_")
    ]


# ---------------------------------------------------------------------------- rendering


def test_every_figure_renders_on_every_shape(dataset):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        figures = {name: make() for name, make in all_figures(dataset).items()}
        for name, fig in figures.items():
            assert isinstance(fig, Figure), name
            FigureCanvasAgg(fig).draw()
            assert fig.axes, name
    # On every shape the curves are the numbers the tables were made from (slope, intercept).
    x, n, runs = dataset["positions"], dataset["n_meas"], dataset["runs"]
    curves = [line.get_ydata() for line in figures["fig5"].axes[0].get_lines()
              if len(line.get_xdata()) == len(x)]  # fmt: skip
    expected = [intercept(m) + slope(0) * (x - x[0]) / 1000.0 for m in range(1, n + 1)]
    np.testing.assert_allclose(curves, expected)
    ax_k, ax_b = figures["fig12"].axes[:2]
    np.testing.assert_allclose(
        [line.get_ydata() for line in lines_of(ax_k)], [[slope(r)] * n for r in range(len(runs))]
    )
    np.testing.assert_allclose(
        [line.get_ydata() for line in lines_of(ax_b)],
        [[intercept(m) for m in range(1, n + 1)]] * len(runs),
    )


def test_figure_functions_leave_global_rcparams_alone(tiny):
    before = dict(matplotlib.rcParams)
    paper_figures.fig5_unzeroed(tiny["errors"], "R1")
    assert dict(matplotlib.rcParams) == before


# ---------------------------------------------------------------------------- determinism


@pytest.mark.parametrize("name", ["fig7", "error_prediction"])
def test_save_figure_is_byte_identical_across_renders(tiny, tmp_path, name):
    make = all_figures(tiny)[name]
    outputs = []
    for attempt in ("a", "b"):
        paths = [tmp_path / attempt / f"{name}.{suffix}" for suffix in ("png", "pdf", "svg")]
        style.save_figure(make(), paths)
        outputs.append([p.read_bytes() for p in paths])
    for suffix, first, second in zip(("png", "pdf", "svg"), *outputs, strict=False):
        assert first, suffix
        assert first == second, f"{name}.{suffix} differs between two renders"
    svg = outputs[0][2].decode()
    assert "<dc:date>" not in svg and "Matplotlib v" not in svg
    assert b"CreationDate" not in outputs[0][1]


def test_a_reused_font_subset_writes_the_pdf_matplotlib_writes_alone(tiny, tmp_path, monkeypatch):
    """save_figure subsets a glyph set's font once per process; every PDF must still be the
    bytes of matplotlib's own writer, which subsets anew each time."""
    from matplotlib.backends import _backend_pdf_ps

    matplotlib_own = _backend_pdf_ps.get_glyphs_subset
    made = []

    def counted(fontfile, glyphs):
        made.append(frozenset(glyphs))
        return matplotlib_own(fontfile, glyphs)

    monkeypatch.setattr(font_subsets, "_make_subset", counted)
    font_subsets._saved_subset.cache_clear()
    make = all_figures(tiny)["error_prediction"]
    for attempt in ("a", "b", "c"):
        style.save_figure(make(), tmp_path / f"{attempt}.pdf")
    assert _backend_pdf_ps.get_glyphs_subset is matplotlib_own  # restored after saving
    with matplotlib.rc_context(style.STYLE):
        make().savefig(tmp_path / "plain.pdf", metadata=style._SAVE_METADATA["pdf"])
    plain = (tmp_path / "plain.pdf").read_bytes()
    assert all((tmp_path / f"{a}.pdf").read_bytes() == plain for a in ("a", "b", "c"))
    assert len(made) == len(set(made)) >= 1  # three PDFs, one subset per glyph set
    font_subsets._saved_subset.cache_clear()


def test_saves_in_two_threads_leave_matplotlibs_subsetter_in_place(tiny, tmp_path):
    import threading

    from matplotlib.backends import _backend_pdf_ps

    matplotlib_own = _backend_pdf_ps.get_glyphs_subset
    entered, release = threading.Barrier(2), threading.Event()

    def save(name):
        with font_subsets.shared_font_subsets():
            entered.wait()
            release.wait()
        style.save_figure(all_figures(tiny)["fig2"](), tmp_path / f"{name}.pdf")

    first = threading.Thread(target=save, args=("a",))
    first.start()
    with font_subsets.shared_font_subsets():
        entered.wait()
        release.set()
        first.join()  # the other thread left first: the hook stays for this one
        assert _backend_pdf_ps.get_glyphs_subset is font_subsets._get_glyphs_subset
    assert _backend_pdf_ps.get_glyphs_subset is matplotlib_own
    assert (tmp_path / "a.pdf").read_bytes()[:5] == b"%PDF-"


def test_save_figure_rejects_an_unknown_suffix_before_writing(tiny, tmp_path):
    fig = paper_figures.fig2_positioning_error(tiny["errors"], "R1")
    with pytest.raises(ValueError, match="suffix"):
        style.save_figure(fig, [tmp_path / "ok.png", tmp_path / "bad.jpg"])
    assert not (tmp_path / "ok.png").exists()


def test_save_figure_accepts_a_single_path_and_creates_folders(tiny, tmp_path):
    target = tmp_path / "deep" / "fig2.png"
    style.save_figure(paper_figures.fig2_positioning_error(tiny["errors"], "R1"), str(target))
    assert target.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# ---------------------------------------------------------------------------- plotted values


def test_fig2_draws_the_first_measurement(tiny):
    (line,) = lines_of(paper_figures.fig2_positioning_error(tiny["errors"], "R2").axes[0])
    # Measurement 1 of run index 1: b = 0, k = -11 um/m over x - 0 mm.
    np.testing.assert_allclose(line.get_xdata(), [0.0, 10.0, 20.0, 30.0])
    np.testing.assert_allclose(line.get_ydata(), [0.0, -0.11, -0.22, -0.33])


def test_fig5_one_curve_per_measurement_labelled_by_time(tiny):
    ax = paper_figures.fig5_unzeroed(tiny["errors"], "R1").axes[0]
    lines = lines_of(ax)
    assert [line.get_label() for line in lines] == ["0 min", "20 min", "40 min"]
    # Measurement 3 of run index 0: b = -1.0, k = -10 um/m.
    np.testing.assert_allclose(lines[2].get_ydata(), [-1.0, -1.1, -1.2, -1.3])
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["0 min", "20 min", "40 min"]


def test_fig5_many_measurements_get_a_colour_bar_instead_of_a_legend():
    d = make_dataset(*SHAPES["five_runs_many_lines"])
    fig = paper_figures.fig5_unzeroed(d["errors"], "R1")
    ax = fig.axes[0]
    assert ax.get_legend() is None
    assert len(lines_of(ax)) == 12
    assert len(fig.axes) == 2 and fig.axes[1].get_ylabel() == style.TIME_LABEL


def test_fig6_one_curve_per_position_against_time(tiny):
    lines = lines_of(paper_figures.fig6_error_vs_time(tiny["errors"], "R1").axes[0])
    assert [line.get_label() for line in lines] == ["0 mm", "10 mm", "20 mm", "30 mm"]
    np.testing.assert_allclose(lines[0].get_xdata(), [0.0, 20.0, 40.0])
    # At the first position the error is the intercept b_m alone.
    np.testing.assert_allclose(lines[0].get_ydata(), [0.0, -0.5, -1.0])
    np.testing.assert_allclose(lines[3].get_ydata(), [-0.3, -0.8, -1.3])


def _quads(fig):
    FigureCanvasAgg(fig).draw()  # 3-D polygons get their projected paths when drawn
    collections = [c for c in fig.axes[0].collections if isinstance(c, Poly3DCollection)]
    return sum(len(c.get_paths()) for c in collections)


def test_fig7_fills_one_cell_per_pair_of_neighbouring_measurements_and_positions(tiny):
    # 3 measurements x 4 positions -> 2 x 3 cells.
    assert _quads(paper_figures.fig7_error_surface(tiny["errors"], "R1")) == 6


def test_fig7_leaves_cells_with_a_missing_reading_open(tiny):
    errors = tiny["errors"].copy()
    hole = (errors["run"] == "R1") & (errors["measurement"] == 2) & (errors["position_mm"] == 10.0)
    errors.loc[hole, "error_um"] = np.nan
    # The middle measurement's second position touches 4 of the 6 cells.
    assert _quads(paper_figures.fig7_error_surface(errors, "R1")) == 2


def test_fig7_single_measurement_draws_the_curve_without_cells(tiny):
    errors = tiny["errors"][tiny["errors"]["measurement"] == 1]
    fig = paper_figures.fig7_error_surface(errors, "R1")
    assert _quads(fig) == 0
    assert len(fig.axes[0].get_lines()) == 1


def test_fig8_plots_rezeroed_values_starting_at_zero(tiny):
    lines = lines_of(paper_figures.fig8_rezeroed(tiny["errors"], "R2").axes[0])
    assert len(lines) == 3
    for line in lines:
        assert line.get_ydata()[0] == 0.0
        # Re-zeroing removes b_m: every measurement shows k * (x - x0) only.
        np.testing.assert_allclose(line.get_ydata(), [0.0, -0.11, -0.22, -0.33])


def test_fig9_one_labelled_panel_per_run_in_a_grid():
    d = make_dataset(5, [0.0, 10.0], 2)
    fig = paper_figures.fig9_other_runs(d["errors"], ["R2", "R3", "R4", "R5", "R1"])
    panels = [ax for ax in fig.axes if ax.get_title(loc="left")]
    assert [ax.get_title(loc="left") for ax in panels] == [
        "(a) Run R2",
        "(b) Run R3",
        "(c) Run R4",
        "(d) Run R5",
        "(e) Run R1",
    ]
    # Two columns: five panels take three rows and the sixth slot is removed.
    assert len(fig.axes) == 5
    assert {ax.get_subplotspec().rowspan.start for ax in panels} == {0, 1, 2}


def test_panel_labels_continue_after_z():
    assert [style._panel_label(i) for i in (0, 1, 25, 26, 27, 51, 52)] == [
        "(a)",
        "(b)",
        "(z)",
        "(aa)",
        "(ab)",
        "(az)",
        "(ba)",
    ]


def test_fig10_rise_is_zero_at_elapsed_zero(tiny):
    lines = lines_of(paper_figures.fig10_temperature_rise(tiny["series"]).axes[0])
    assert [line.get_label() for line in lines] == ["T1", "T2", "T3"]
    for i, line in enumerate(lines):
        x, y = np.asarray(line.get_xdata()), np.asarray(line.get_ydata())
        assert y[x == 0.0] == pytest.approx([0.0], abs=1e-12)
        # T_i = 20 + i + 0.05 (i + 1) t, so the rise at t = 40 min is 2 (i + 1) degrees C.
        assert y[x == 40.0] == pytest.approx([2.0 * (i + 1)])


def test_fig10_interpolates_the_reference_when_no_sample_is_at_zero(tiny):
    series = tiny["series"].copy()
    series.loc[series["elapsed_min"] == 0.0, "T2"] = np.nan
    (line,) = lines_of(paper_figures.fig10_temperature_rise(series, sensors=["T2"]).axes[0])
    x, y = np.asarray(line.get_xdata()), np.asarray(line.get_ydata())
    assert 0.0 not in x
    # T2 is linear, so the interpolated reference is its value at 0 and the rise stays 0.1 t.
    np.testing.assert_allclose(y, 0.1 * x)


def test_fig10_rejects_an_unknown_sensor(tiny):
    with pytest.raises(ValueError, match="T99"):
        paper_figures.fig10_temperature_rise(tiny["series"], sensors=["T1", "T99"])


def test_fig12_k_on_top_and_b_below_one_line_per_run(tiny):
    ax_k, ax_b = paper_figures.fig12_slope_intercept(tiny["kb"]).axes
    k_lines, b_lines = lines_of(ax_k), lines_of(ax_b)
    assert [line.get_label() for line in k_lines] == ["Run R1", "Run R2"]
    np.testing.assert_allclose(k_lines[1].get_ydata(), [-11.0, -11.0, -11.0])
    np.testing.assert_allclose(b_lines[0].get_ydata(), [0.0, -0.5, -1.0])
    np.testing.assert_allclose(b_lines[0].get_xdata(), [1, 2, 3])


def test_fig12_orders_runs_naturally():
    kb = pd.DataFrame(
        dict(
            run=["E10", "E2", "E10", "E2"],
            measurement=[1, 1, 2, 2],
            k_um_per_m=[1.0, 2.0, 3.0, 4.0],
            b_um=0.0,
        )
    )
    ax_k = paper_figures.fig12_slope_intercept(kb).axes[0]
    assert [line.get_label() for line in lines_of(ax_k)] == ["Run E2", "Run E10"]


def test_long_names_keep_their_ends_and_stay_distinct():
    long = "run_" + "x" * 40
    shown = style.short_names([f"{long}_0", f"{long}_1", "R3"])
    # 20 characters: the first 9, an ellipsis, the last 10.
    assert shown == {
        f"{long}_0": "run_xxxxx…xxxxxxxx_0",
        f"{long}_1": "run_xxxxx…xxxxxxxx_1",
        "R3": "R3",
    }
    # Names that differ only in the middle widen (21 characters) until they differ.
    dates = ["2026-03-01_spindle_warmup_A", "2026-03-02_spindle_warmup_A"]
    assert list(style.short_names(dates).values()) == [
        "2026-03-01…e_warmup_A",
        "2026-03-02…e_warmup_A",
    ]


def test_long_run_and_sensor_names_leave_room_for_the_axes():
    long = "run_" + "x" * 40
    runs = [f"{long}_{i}" for i in range(3)]
    stability = pd.DataFrame(
        [
            dict(fold=fold, target=target, sensor=f"sensor_{'y' * 30}_{s}", chosen=s == 0,
                 frequency=0.5)
            for fold in runs for target in ("k", "b", "pointwise") for s in range(5)
        ]
    )  # fmt: skip
    kb = pd.DataFrame(
        dict(run=np.repeat(runs, 2), measurement=[1, 2] * 3, k_um_per_m=1.0, b_um=0.0)
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # "constrained_layout not applied" among them
        for fig in (statistics_figures.fig_selection_stability(stability),
                    paper_figures.fig12_slope_intercept(kb)):  # fmt: skip
            FigureCanvasAgg(fig).draw()
            for ax in fig.axes:
                box = ax.get_position()
                wide = 0.1 if ax.get_label() != "<colorbar>" else 0.0
                assert box.width > wide and box.height > 0.1
    legend = [line.get_label() for line in lines_of(fig.axes[0])]
    assert legend == [
        "Run run_xxxxx…xxxxxxxx_0",
        "Run run_xxxxx…xxxxxxxx_1",
        "Run run_xxxxx…xxxxxxxx_2",
    ]


def test_the_top_legend_takes_fewer_columns_only_where_four_would_overrun_the_figure():
    recommendation = pd.DataFrame(
        dict(fold=["E1", "E2"], rmse_um=1.0, max_abs_um=2.0, paper_rmse_um=1.5,
             paper_max_abs_um=2.5)
    )  # fmt: skip
    fig = prediction_figures.fig_recommendation(recommendation)
    FigureCanvasAgg(fig).draw()
    (legend,) = fig.legends
    # "paper's configuration, held out" beside "recommendation, held out" is wider than
    # a single column's 3.5 in: one above the other.
    assert legend._ncols == 1
    assert legend.get_window_extent().width <= fig.bbox.width
    runs = pd.DataFrame(dict(run=["E1", "E2", "E3", "E4"], measurement=1, k_um_per_m=1.0, b_um=0.0))
    (legend,) = paper_figures.fig12_slope_intercept(runs).legends
    assert legend._ncols == 4


def _bands(ax):
    return [c for c in ax.collections if isinstance(c, PolyCollection)]


def test_kb_prediction_shades_the_interval_only_when_given(tiny):
    fig = prediction_figures.fig_kb_prediction(tiny["kb_pred"], "R2", "decoupled", "gpr")
    ax_k, ax_b = fig.axes
    measured, predicted = lines_of(ax_k)
    np.testing.assert_allclose(measured.get_ydata(), [-11.0, -11.0, -11.0])
    np.testing.assert_allclose(predicted.get_ydata(), [-10.75, -10.75, -10.75])
    assert predicted.get_label() == "Predicted (GPR)"
    assert len(_bands(ax_k)) == 1 and len(_bands(ax_b)) == 1
    no_band = prediction_figures.fig_kb_prediction(tiny["kb_pred"], "R2", "decoupled", "mlr")
    assert all(not _bands(ax) for ax in no_band.axes)


def test_error_prediction_draws_measured_predicted_and_residual(tiny):
    fig = prediction_figures.fig_error_prediction(tiny["err_pred"], "R1", "decoupled", "mlr")
    ax_curve, ax_res = fig.axes[:2]
    curves = ax_curve.get_lines()
    assert len(curves) == 2 * 3  # measured + predicted per measurement
    np.testing.assert_allclose(curves[0].get_ydata(), [0.0, -0.1, -0.2, -0.3])
    np.testing.assert_allclose(curves[1].get_ydata(), [-0.125, -0.225, -0.325, -0.425])
    residuals = lines_of(ax_res)
    assert len(residuals) == 3
    assert all(np.allclose(line.get_ydata(), 0.125) for line in residuals)


def test_fig11_draws_the_pointwise_rows(tiny):
    err_pred = tiny["err_pred"].copy()
    pointwise = err_pred["approach"] == "pointwise"
    err_pred.loc[pointwise, "residual"] = 0.75
    ax_res = prediction_figures.fig_error_prediction(err_pred, "R1", "pointwise", "mlr").axes[1]
    assert all(np.allclose(line.get_ydata(), 0.75) for line in lines_of(ax_res))


def test_fold_comparison_bar_heights_are_the_metrics(tiny):
    fig = prediction_figures.fig_fold_comparison(tiny["metrics"])
    ax_rmse, ax_max = fig.axes
    # Pairs sorted: (decoupled, gpr), (decoupled, mlr), (pointwise, mlr); folds R1, R2.
    heights = [p.get_height() for p in ax_rmse.patches]
    np.testing.assert_allclose(heights, [0.11, 0.21, 0.1, 0.2, 0.1, 0.2])
    np.testing.assert_allclose([p.get_height() for p in ax_max.patches], [0.2, 0.4] * 3)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["decoupled, GPR", "decoupled, MLR", "point-by-point, MLR"]


def test_fold_comparison_whiskers_span_the_interval_even_where_it_misses_the_bar(tiny):
    # A percentile interval need not contain its estimate: the tables' rounding put a
    # max |residual| 1e-6 above its bootstrap's upper end, which matplotlib refused as a
    # negative error. The whisker is the interval itself.
    metrics = tiny["metrics"]
    metrics = metrics[metrics["target"] == "error"].reset_index(drop=True)  # the figure's rows
    for column in ("rmse", "max_abs"):
        metrics[f"{column}_lo"] = metrics[column] - 0.05
        metrics[f"{column}_hi"] = metrics[column] + 0.05
    metrics.loc[0, "max_abs_lo"] = metrics.loc[0, "max_abs"] - 0.1
    metrics.loc[0, "max_abs_hi"] = metrics.loc[0, "max_abs"] - 1e-6
    ax_max = prediction_figures.fig_fold_comparison(metrics).axes[1]
    spans = sorted(
        (round(seg[0][1], 9), round(seg[1][1], 9))
        for collection in ax_max.collections
        for seg in collection.get_segments()
    )
    expected = sorted(
        (round(lo, 9), round(hi, 9))
        for lo, hi in zip(metrics["max_abs_lo"], metrics["max_abs_hi"], strict=True)
    )
    assert spans == expected


def test_fold_comparison_leaves_a_gap_for_a_missing_pair(tiny):
    metrics = tiny["metrics"]
    drop = (metrics["fold"] == "R2") & (metrics["algorithm"] == "gpr")
    ax_rmse = prediction_figures.fig_fold_comparison(metrics[~drop]).axes[0]
    assert len(ax_rmse.patches) == 5


# ---------------------------------------------------------------------------- bad input


def test_unknown_run_names_the_available_runs(tiny):
    with pytest.raises(ValueError, match=r"run='R9'.*R1, R2"):
        paper_figures.fig5_unzeroed(tiny["errors"], "R9")


def test_missing_column_is_named(tiny):
    with pytest.raises(ValueError, match="rezeroed_um"):
        paper_figures.fig8_rezeroed(tiny["errors"].drop(columns="rezeroed_um"), "R1")


def test_unknown_fold_is_named(tiny):
    with pytest.raises(ValueError, match="fold='R7'"):
        prediction_figures.fig_kb_prediction(tiny["kb_pred"], "R7", "decoupled", "mlr")


def test_fig9_needs_a_run(tiny):
    with pytest.raises(ValueError, match="at least one run"):
        paper_figures.fig9_other_runs(tiny["errors"], [])


# ---------------------------------------------------------------------------- captions

CAPTION_DETAILS = {
    "fig2_positioning_error": dict(run="E1"),
    "fig3_ambient": {},
    "fig5_unzeroed": dict(run="E1"),
    "fig6_error_vs_time": dict(run="E1"),
    "fig7_error_surface": dict(run="E1"),
    "fig8_rezeroed": dict(run="E1"),
    "fig9_other_runs": dict(runs=["E2", "E3", "E4"]),
    "fig10_temperature_rise": dict(run="E1"),
    "fig12_slope_intercept": {},
    "kb_prediction": dict(fold="E4", approach="decoupled", algorithm="gpr"),
    "error_prediction": dict(fold="E4", approach="decoupled", algorithm="gpr"),
    "fold_comparison": dict(target="error"),
    "compensation_drift": dict(fold="E4"),
}
PHRASE = "Simulated data (thermal twin), not the paper's measurements."


@pytest.mark.parametrize("figure_id", list(CAPTION_DETAILS))
@pytest.mark.parametrize("simulated", [True, False])
def test_caption_has_the_simulated_phrase_iff_simulated(figure_id, simulated):
    caption = captions.figure_caption(figure_id, "twin", simulated, **CAPTION_DETAILS[figure_id])
    assert (PHRASE in caption) is simulated
    assert "twin" in caption and "{" not in caption


def test_a_simulated_dataset_other_than_the_twin_is_not_called_the_twin():
    caption = captions.figure_caption("fig5_unzeroed", "scale", True, twin=False, run="E1")
    assert caption.endswith("Dataset: scale. Simulated data, not measurements of a machine.")
    assert "thermal twin" not in caption
    assert captions.provenance_note(False, twin=False) is None


def test_caption_fills_details_and_names_the_paper_figure():
    caption = captions.figure_caption("fig9_other_runs", "lab", False, runs=["E2", "E3"])
    assert "runs E2, E3" in caption and "paper's Fig. 9." in caption
    svr = captions.figure_caption(
        "kb_prediction", "lab", False, fold="E4", approach="decoupled", algorithm="svr"
    )
    assert svr.count("SVR") == 1 and "paper's Fig. 14/16." in svr
    # The point-by-point error prediction is the paper's Fig. 11, which names no approach.
    pointwise = captions.figure_caption(
        "error_prediction", "lab", False, fold="E4", approach="pointwise", algorithm="mlr"
    )
    assert (
        pointwise.startswith("Point-by-point prediction (MLR)") and "paper's Fig. 11." in pointwise
    )


@pytest.mark.parametrize(
    "args, kwargs, match",
    [
        (("fig99", "twin", True), {}, "unknown figure id"),
        (("fig5_unzeroed", "twin", True), {}, "missing \\['run'\\]"),
        (("fig5_unzeroed", "twin", True), dict(run="E1", rn="E1"), "unexpected \\['rn'\\]"),
        (("fig3_ambient", "", True), {}, "dataset_name"),
        (("fig5", "twin", True), dict(run="E1"), "unknown figure id"),
    ],
)
def test_caption_rejects_bad_requests(args, kwargs, match):
    with pytest.raises(ValueError, match=match):
        captions.figure_caption(*args, **kwargs)


# ---------------------------------------------------------------------------- provenance and ids


@pytest.mark.parametrize("name", ["fig5", "fig7"])
def test_stamp_provenance_adds_the_note_once(tiny, name):
    fig = style.stamp_provenance(all_figures(tiny)[name]())
    texts = [t.get_text() for t in fig.texts]  # a supxlabel is one of them too
    assert texts.count(PHRASE) == 1
    FigureCanvasAgg(fig).draw()


def test_save_figure_dpi_sets_the_png_size(tiny, tmp_path):
    from PIL import Image

    style.save_figure(
        paper_figures.fig2_positioning_error(tiny["errors"], "R1"), tmp_path / "f.png", dpi=100
    )
    # fig2 is 3.5 in x 2.4 in.
    assert Image.open(tmp_path / "f.png").size == (350, 240)


def test_integer_ids_match_their_text_form(tiny):
    kb_pred = tiny["kb_pred"].assign(fold=tiny["kb_pred"]["fold"].str[1:].astype(int))
    fig = prediction_figures.fig_kb_prediction(kb_pred, "2", "decoupled", "mlr")
    np.testing.assert_allclose(lines_of(fig.axes[0])[0].get_ydata(), [-11.0, -11.0, -11.0])


def test_fig10_with_many_sensors_names_those_that_rise_most():
    # 30 sensors, sensor j rising 0.01 j degC per minute: T16..T30 rise most. Fifteen are
    # named (in their order), the other fifteen are grey and one legend entry.
    t = np.arange(0.0, 61.0, 5.0)
    series = pd.DataFrame(
        {"elapsed_min": t, **{f"T{j}": 20.0 + 0.01 * j * t for j in range(1, 31)}}
    )
    fig = paper_figures.fig10_temperature_rise(series)
    labels = [text.get_text() for text in fig.legends[0].get_texts()]
    assert labels == ["other 15 sensors"] + [f"T{j}" for j in range(16, 31)]
    # Every sensor is drawn (the one more line is the zero reference).
    assert len(fig.axes[0].get_lines()) == 31
    named = {line.get_label(): line for line in lines_of(fig.axes[0])}
    np.testing.assert_allclose(named["T30"].get_ydata(), 0.3 * t)


def test_a_sweep_that_varies_no_cluster_count_draws_a_heat_map_saying_so():
    # A one-sensor dataset: no n_clusters of the grid fits, only 'all' and 'fixed' ran.
    from thermaxis.figures.sweep import fig_sweep_heatmap

    fig = fig_sweep_heatmap({"decoupled": pd.DataFrame(), "pointwise": pd.DataFrame()})
    (ax,) = fig.axes
    assert not ax.axison
    assert [t.get_text().startswith("No configuration of this sweep varies") for t in ax.texts] == [
        True
    ]
