#!/usr/bin/env python3
"""Sweep the Ray Shooting planner's horizon on a job and plot the objective J against it.

    PYTHONPATH=build/python python3 examples/python/sweep_horizon.py -o out/horizon.png

Each horizon plans the job twice (maps, table path, trajectory; no simulation): with the
default cost-to-go at each ray's end, and with the paper's plain rays (planner.ray.cost_to_go:
false). The exact DP's J on the same maps is the floor both approach.
"""
import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402

import scanplan  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[2]


def objective(job, overrides, planner):
    """J of the job planned with `overrides` (None when it has no path)."""
    plan = scanplan.plan(scanplan.load_job(job, overrides=overrides).problem(), planner=planner)
    if plan.trajectory is None:
        print(f"  {planner}: {plan.status} ({plan.reason})")
        return None
    return plan.objective["J"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("job", nargs="?", default=REPO / "data" / "jobs" / "demo_rings.yaml")
    parser.add_argument("--horizons", default="1,2,3,5,8,12,20",
                        help="planner.ray.horizon values, in samples (default: %(default)s)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a job override, as `scanplan plan --set`")
    parser.add_argument("-o", "--output", default="horizon.png", help="the figure (PNG)")
    args = parser.parse_args()

    base = args.set + ["simulation.enabled=false"]
    horizons = [int(h) for h in args.horizons.split(",")]
    j_dp = objective(args.job, base, "dp")
    series = {"cost-to-go (default)": "true", "plain rays (the paper's)": "false"}
    curves = {name: [] for name in series}
    for h in horizons:
        line = f"horizon {h:3d}:"
        for name, cost_to_go in series.items():
            j = objective(args.job, base + [f"planner.ray.horizon={h}",
                                            f"planner.ray.cost_to_go={cost_to_go}"], "ray")
            curves[name].append(j)
            gap = f" ({100 * (j / j_dp - 1):5.1f} % above the DP)" if j and j_dp else ""
            line += f"  {name.split()[0]} J {j:8.3f} s{gap}" if j else f"  {name}: no path"
        print(line)

    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=120)
    for name, values in curves.items():
        points = [(h, j) for h, j in zip(horizons, values) if j is not None]
        ax.plot([p[0] for p in points], [p[1] for p in points], "o-", label=f"ray, {name}")
    if j_dp:
        ax.axhline(j_dp, color="k", lw=1, ls="--", label=f"exact DP: J {j_dp:.2f} s")
    ax.set_xticks(horizons)
    ax.set_xlabel("planner.ray.horizon (samples)")
    ax.set_ylabel("objective J (s)")
    ax.set_title(f"Ray Shooting horizon on {pathlib.Path(args.job).stem}")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.output)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
