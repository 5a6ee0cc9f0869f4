"""The examples in examples/python/, run as a user runs them, on light settings.

Each example's figures and files are read back and checked: the PNG is a picture, the PLY holds
the plan's points coloured by incidence, the printed figures obey the planner's guarantees.
"""
import os
import pathlib
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("scanplan", reason="the scanplan module is not built")

SOURCE = pathlib.Path(os.environ.get("SCANPLAN_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
EXAMPLES = SOURCE / "examples" / "python"
RINGS = SOURCE / "data" / "jobs" / "demo_rings.yaml"
LIGHT = ["--set", "scan.dt_s=0.2"]


def run_example(name, *args, display=False):
    """Runs examples/python/NAME with this interpreter and module; returns its stdout."""
    command = [sys.executable, str(EXAMPLES / name), *map(str, args)]
    if display and not os.environ.get("DISPLAY"):
        if not shutil.which("xvfb-run"):
            pytest.skip("rendering needs an X display or xvfb-run (Debian's xvfb)")
        command = ["xvfb-run", "-a"] + command
    run = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    return run.stdout


def read_png(path):
    image = pytest.importorskip("matplotlib.image").imread(path)
    assert image.ndim == 3 and image.shape[0] > 100 and image.shape[1] > 100
    return image


def test_sweep_horizon_plots_j_against_the_horizon(tmp_path):
    pytest.importorskip("matplotlib", reason="the example needs python3-matplotlib")
    out = run_example("sweep_horizon.py", RINGS, *LIGHT, "--horizons", "2,5,12",
                      "-o", tmp_path / "horizon.png")
    rows = re.findall(r"horizon +(\d+): +cost-to-go J +([\d.]+) s.*plain J +([\d.]+) s", out)
    assert [int(r[0]) for r in rows] == [2, 5, 12], out
    for _, with_cost_to_go, plain in rows:
        assert float(with_cost_to_go) > 0 and float(plain) > 0
    image = read_png(tmp_path / "horizon.png")
    assert (image[..., :3] < 0.5).any()  # lines drawn, not a blank canvas


def test_cloud_by_incidence_colours_the_plans_cloud(tmp_path):
    o3d = pytest.importorskip("open3d", reason="the example needs python3-open3d")
    out = run_example("cloud_by_incidence.py", RINGS, *LIGHT, "--image", tmp_path / "cloud.png",
                      "--ply", tmp_path / "cloud.ply", display=True)
    count = int(re.search(r"^(\d+) points", out, re.M).group(1))
    cloud = o3d.io.read_point_cloud(str(tmp_path / "cloud.ply"))
    assert len(cloud.points) == count > 0 and cloud.has_colors() and cloud.has_normals()
    # Coloured by incidence: many distinct colours, each a valid RGB.
    colours = np.asarray(cloud.colors)
    assert np.all((colours >= 0) & (colours <= 1))
    assert len(np.unique(np.round(colours, 2), axis=0)) > 10
    image = read_png(tmp_path / "cloud.png")
    assert (image[..., :3] < 0.9).any(axis=2).mean() > 0.02  # the part and the cloud fill it


def test_compare_robots_plans_both_within_their_limits():
    out = run_example("compare_robots.py", RINGS, SOURCE / "data/robots/viper_s650.yaml",
                      SOURCE / "data/robots/kuka_kr6_r900_sixx.yaml", *LIGHT)
    assert re.findall(r"^(\S+): planned$", out, re.M) == ["viper_s650", "kuka_kr6_r900_sixx"]
    assert len(re.findall(r"program +[\d.]+ s: [\d.]+ s scanning", out)) == 2
    # A valid program drives no joint past its limit (the trajectory's own finite differences).
    shares = [int(s) for s in re.findall(r"j\d \d+ \((\d+) %\)", out)]
    assert len(shares) == 12 and max(shares) <= 100
