"""Resource requests from recorded benchmarks (numbers worked out by hand)."""

from __future__ import annotations

from thermaxis.pipeline import resources

RULES = """
rule clean_run:
    output:
        f"{OUT}/clean/{{run}}/qc.csv",
    benchmark:
        f"{BENCH}/clean/{{run}}.tsv"
    script:
        "x.py"


rule sweep:
    input:
        "a",


rule sweep_batch:
    benchmark:
        f"{BENCH}/sweep/batch_{{n_batches}}_{{batch}}.tsv"
"""


def test_benchmark_globs_follow_the_rule_files():
    assert resources.benchmark_globs([RULES]) == {
        "clean_run": "clean/*.tsv",
        "sweep_batch": "sweep/batch_*_*.tsv",
    }


def test_requests_by_hand():
    # 2 x 300 MB = 600 -> next 250 MB step 750; 5 x 100 s = 500 s -> 8.3 -> 9 min.
    assert resources.request(100.0, 300.0) == (750, 9)
    # Small jobs get the floors: 500 MB, 5 min.
    assert resources.request(2.0, 120.0) == (500, 5)


def test_requests_take_the_worst_benchmark_of_a_rule(tmp_path):
    bench = tmp_path / "clean"
    bench.mkdir()
    header = "s\th:m:s\tmax_rss\tmax_vms\n"
    (bench / "R1.tsv").write_text(header + "10.0\t0:00:10\t200.0\t900\n")
    (bench / "R2.tsv").write_text(header + "90.0\t0:01:30\t-\t900\n")  # memory not sampled
    [req] = resources.requests_from_benchmarks(
        tmp_path, {"clean_run": "clean/*.tsv", "sweep_batch": "sweep/*.tsv"}
    )
    # Worst: 90 s and 200 MB -> 2 x 200 = 400 -> 500 floor; 5 x 90 = 450 s -> 7.5 -> 8 min.
    assert (req.rule, req.n_benchmarks, req.max_s, req.max_rss_mb, req.mem_mb, req.runtime_min) == (
        "clean_run", 2, 90.0, 200.0, 500, 8,
    )  # fmt: skip


def test_per_attempt_scales_memory_and_runtime_with_the_attempt():
    fixed = resources.per_attempt(750, 5)
    assert fixed["mem_mb"]({}, 1) == 750 and fixed["mem_mb"]({}, 3) == 2250
    assert fixed["runtime"]({}, 2) == 10
    # A runtime from the job's wildcards (a sweep batch's share of the grid).
    derived = resources.per_attempt(500, lambda wildcards: int(wildcards["batch"]) + 1)
    assert derived["runtime"]({"batch": "2"}, 2) == 6


def test_a_benchmark_one_rule_names_exactly_is_not_another_rules(tmp_path):
    bench = tmp_path / "compensation"
    bench.mkdir()
    header = "s\th:m:s\tmax_rss\tmax_vms\n"
    (bench / "model.tsv").write_text(header + "60.0\t0:01:00\t300.0\t900\n")
    (bench / "E1.tsv").write_text(header + "5.0\t0:00:05\t100.0\t900\n")
    globs = {
        "compensation_model": "compensation/model.tsv",
        "compensation_fold": "compensation/*.tsv",
    }
    fold, model = resources.requests_from_benchmarks(tmp_path, globs)
    assert (fold.rule, fold.n_benchmarks, fold.max_s) == ("compensation_fold", 1, 5.0)
    assert (model.rule, model.n_benchmarks, model.max_s) == ("compensation_model", 1, 60.0)
