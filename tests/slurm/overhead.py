"""Scheduler overhead per job of a finished Snakemake run under profiles/slurm.

    python tests/slurm/overhead.py WORKDIR [--log .snakemake/log/<run>.snakemake.log]

For every job of the run (default: the newest Snakemake log in WORKDIR) it joins three
records: the Snakemake log (rule, benchmark file, Slurm job id, when Snakemake saw the
job finish), `sacct` (submitted, started, ended) and the rule's benchmark (seconds the
rule itself ran). Per job:

- queue: started - submitted (waiting for the scheduler and a free CPU);
- in-job start-up: (ended - started) - the rule's own seconds (Snakemake starting and
  parsing the workflow inside the job, srun);
- noticed: Snakemake's "Finished" time - ended (the status-check interval).

Prints one JSON object: means and totals over the jobs, and the per-job rows.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from datetime import datetime
from pathlib import Path

import pandas as pd

_STAMP = re.compile(r"^\[(\w{3} \w{3} +\d+ \d\d:\d\d:\d\d \d{4})\]$")
_RULE = re.compile(r"^(?:local)?rule (\w+):$")
_JOBID = re.compile(r"^\s+jobid: (\d+)$")
_BENCH = re.compile(r"^\s+benchmark: (\S+)$")
_SUBMITTED = re.compile(r"^Job (\d+) has been submitted with SLURM jobid (\d+)")
_FINISHED = re.compile(r"^Finished jobid: (\d+)")


def parse_log(text: str) -> pd.DataFrame:
    """One row per Snakemake job id: rule, slurm_id, finished (the log's time stamp)."""
    jobs: dict[str, dict] = {}
    stamp, rule = None, None
    for line in text.splitlines():
        if m := _STAMP.match(line):
            stamp = datetime.strptime(m.group(1), "%a %b %d %H:%M:%S %Y")
        elif m := _RULE.match(line):
            rule = m.group(1)
        elif m := _JOBID.match(line):
            jobs.setdefault(m.group(1), {})["rule"] = rule
        elif m := _SUBMITTED.match(line):
            jobs.setdefault(m.group(1), {})["slurm_id"] = m.group(2)
        elif m := _FINISHED.match(line):
            jobs.setdefault(m.group(1), {})["finished"] = stamp
    return pd.DataFrame.from_dict(jobs, orient="index")


def benchmarks_by_job(text: str) -> dict[str, str]:
    """{snakemake jobid: benchmark path} from the job blocks of the log."""
    out, block = {}, {}
    for line in text.splitlines():
        if _RULE.match(line):
            block = {}
        elif m := _BENCH.match(line):
            block["benchmark"] = m.group(1)
        elif m := _JOBID.match(line):
            block["jobid"] = m.group(1)
        if "benchmark" in block and "jobid" in block:
            out[block["jobid"]] = block["benchmark"]
            block = {}
    return out


def sacct_times(ids) -> pd.DataFrame:
    proc = subprocess.run(
        ["sacct", "-n", "-X", "-P", "-j", ",".join(ids), "-o", "JobIDRaw,Submit,Start,End,State"],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    rows = [line.split("|") for line in proc.stdout.splitlines() if line]
    frame = pd.DataFrame(rows, columns=["slurm_id", "submit", "start", "end", "state"])
    for column in ("submit", "start", "end"):
        frame[column] = pd.to_datetime(frame[column])
    return frame


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("workdir", type=Path)
    parser.add_argument("--log", type=Path, default=None)
    args = parser.parse_args(argv)
    log = args.log or max((args.workdir / ".snakemake" / "log").glob("*.snakemake.log"))
    text = log.read_text()
    jobs = parse_log(text)
    jobs["benchmark"] = pd.Series(benchmarks_by_job(text))
    jobs = jobs.dropna(subset=["slurm_id", "finished"])
    times = sacct_times(jobs["slurm_id"])
    jobs = jobs.merge(times, on="slurm_id")
    jobs = jobs[jobs["state"] == "COMPLETED"].copy()
    jobs["rule_s"] = [
        float(pd.read_csv(args.workdir / b, sep="\t")["s"].iloc[0]) for b in jobs["benchmark"]
    ]
    jobs["queue_s"] = (jobs["start"] - jobs["submit"]).dt.total_seconds()
    jobs["elapsed_s"] = (jobs["end"] - jobs["start"]).dt.total_seconds()
    jobs["startup_s"] = jobs["elapsed_s"] - jobs["rule_s"]
    jobs["noticed_s"] = (jobs["finished"] - jobs["end"]).dt.total_seconds()
    jobs["overhead_s"] = jobs["queue_s"] + jobs["startup_s"] + jobs["noticed_s"]
    columns = ["rule", "slurm_id", "rule_s", "queue_s", "startup_s", "noticed_s", "overhead_s"]
    summary = {
        "log": str(log),
        "jobs": int(len(jobs)),
        "mean": {c: round(float(jobs[c].mean()), 2) for c in columns[2:]},
        "total": {c: round(float(jobs[c].sum()), 2) for c in columns[2:]},
        "per_job": jobs[columns].round(2).to_dict("records"),
    }
    json.dump(summary, sys.stdout, indent=1, default=str)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
