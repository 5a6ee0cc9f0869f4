#!/usr/bin/env python3
"""CPU time of planning a job through the Python module against the scanplan command.

    PYTHONPATH=build/python python3 tests/bench/bench_python.py [JOB] [--runs N]

Each run plans JOB (default data/jobs/demo_rings.yaml) once with `scanplan plan` (its CPU time,
user + system, from the child's resource usage) and once with scanplan.plan() in this process
(the process's CPU time around the call), alternating; it prints both per run, their medians and
the ratio python / command (target: at most 1.02). The command also writes its output files,
which the Python call does not: the ratio is an upper bound of the module's own overhead.
"""
import argparse
import os
import pathlib
import resource
import statistics
import subprocess
import tempfile
import time

import scanplan

SOURCE = pathlib.Path(__file__).resolve().parents[2]


def cli_cpu(binary, job, out):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([binary, "plan", str(job), "-o", str(out)], check=True,
                   stdout=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def python_cpu(job):
    start = time.process_time()
    plan = scanplan.plan(scanplan.load_job(job).problem())
    cpu = time.process_time() - start
    assert plan.status == "planned", plan.reason
    return cpu


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("job", nargs="?", default=SOURCE / "data" / "jobs" / "demo_rings.yaml")
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--binary", default=os.environ.get("SCANPLAN_BINARY",
                                                           SOURCE / "build" / "scanplan"))
    args = parser.parse_args()
    cli, py = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.runs):
            cli.append(cli_cpu(args.binary, args.job, pathlib.Path(tmp) / f"run{k}"))
            py.append(python_cpu(args.job))
            print(f"run {k + 1}: command {cli[-1]:.2f} s CPU, python {py[-1]:.2f} s CPU")
    c, p = statistics.median(cli), statistics.median(py)
    print(f"median: command {c:.2f} s, python {p:.2f} s CPU; python / command = {p / c:.3f} "
          f"(target <= 1.02)")


if __name__ == "__main__":
    main()
