#!/usr/bin/env python3
"""Plan the same job on two robots and compare their programs.

    PYTHONPATH=build/python python3 examples/python/compare_robots.py
    PYTHONPATH=build/python python3 examples/python/compare_robots.py data/jobs/demo_rings.yaml \\
        data/robots/viper_s650.yaml data/robots/kuka_kr6_r900_sixx.yaml --set scan.dt_s=0.2

The job's robot is replaced by each robot file in turn (the cell, part and scan stay). For each
robot it prints the program time and its split, the coverage, the closest approach and how hard
the program drives each joint: the fastest joint speed in the trajectory against the robot's limit.
"""
import argparse
import pathlib

import numpy as np

import scanplan

REPO = pathlib.Path(__file__).resolve().parents[2]


def joint_use(robot, trajectory):
    """Per joint: the fastest speed in `trajectory` (rad/s) and its share of the robot's limit."""
    t, q = trajectory[:, 0], trajectory[:, 2:]
    speed = np.abs(np.diff(q, axis=0) / np.diff(t)[:, None]).max(axis=0)
    return speed, speed / np.asarray(robot.max_speed)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    robots = REPO / "data" / "robots"
    parser.add_argument("job", nargs="?", default=REPO / "data" / "jobs" / "demo.yaml")
    parser.add_argument("robots", nargs="*",
                        default=[robots / "viper_s650.yaml", robots / "kuka_kr6_r900_sixx.yaml"])
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a job override, as `scanplan plan --set`")
    args = parser.parse_args()

    for path in args.robots:
        path = pathlib.Path(path).resolve()
        robot = scanplan.load_robot(path)
        job = scanplan.load_job(args.job, overrides=args.set + [f"robot={path}"])
        plan = scanplan.plan(job.problem())
        print(f"{path.stem}: {plan.status}" + (f" ({plan.reason})" if plan.reason else ""))
        limits = ", ".join(f"{np.degrees(v):.0f}" for v in robot.max_speed)
        print(f"  joint speed limits  {limits} deg/s")
        if plan.trajectory is None:
            continue
        p = plan.program
        print(f"  program             {p['total']:.1f} s: {p['scanning']:.1f} s scanning, "
              f"{p['moving']:.1f} s moving ({p['moves']} moves)")
        if plan.coverage:
            print(f"  coverage            {100 * plan.coverage['area_fraction']:.1f} % of the "
                  f"part's area, {plan.coverage['points']} points")
        v = plan.validation
        if v and v["min_distance"] is not None:
            print(f"  closest approach    {1000 * v['min_distance']:.1f} mm "
                  f"({v['min_distance_pair']} at t = {v['min_distance_t']:.2f} s)")
        speed, share = joint_use(robot, plan.trajectory)
        print("  fastest joint speed " + ", ".join(
            f"j{j + 1} {np.degrees(s):.0f} ({100 * u:.0f} %)" for j, (s, u) in
            enumerate(zip(speed, share))) + " deg/s (of the limit)")


if __name__ == "__main__":
    main()
