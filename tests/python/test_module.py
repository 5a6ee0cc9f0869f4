"""The Python module against the command line and against known answers (python/*.cpp).

Run by ctest (tests/CMakeLists.txt) with PYTHONPATH=build/python; SCANPLAN_BINARY and
SCANPLAN_SOURCE_DIR name the scanplan executable and the source tree.
"""
import json
import os
import pathlib
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

scanplan = pytest.importorskip(
    "scanplan", reason="the scanplan module is not built (it needs python3-dev and pybind11-dev)")

SOURCE = pathlib.Path(os.environ.get("SCANPLAN_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
BINARY = os.environ.get("SCANPLAN_BINARY", str(SOURCE / "build" / "scanplan"))
RINGS = SOURCE / "data" / "jobs" / "demo_rings.yaml"
# The light demo: two rings every 0.2 s (a few seconds with the simulation).
LIGHT = {
    "scan.dt_s": 0.2,
    "scan.paths": "[{type: ring, height_mm: 35, tilt_deg: 25}, {type: ring, height_mm: 105, "
                  "tilt_deg: 60}]",
}


def set_args(overrides):
    args = []
    for key, value in overrides.items():
        args += ["--set", f"{key}={value if isinstance(value, str) else repr(value)}"]
    return args


@pytest.fixture(scope="module")
def light_runs(tmp_path_factory):
    """The light demo planned by the command line (into a folder) and through Python."""
    out = tmp_path_factory.mktemp("cli") / "light"
    run = subprocess.run([BINARY, "plan", str(RINGS), "-o", str(out)] + set_args(LIGHT),
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    plan = scanplan.plan(scanplan.load_job(RINGS, overrides=LIGHT).problem())
    return out, plan


def test_trajectory_equals_the_command_lines_csv(light_runs):
    out, plan = light_runs
    assert plan.status == "planned" and plan.reason == ""
    csv = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True, dtype=None,
                        encoding="utf-8")
    traj = plan.trajectory
    assert traj.shape == (len(csv), 8)
    # trajectory.csv holds 12 significant digits: 5e-10 at most on values below 1000.
    assert np.allclose(traj[:, 0], csv["t_s"], rtol=0, atol=1e-9)
    assert np.allclose(np.degrees(traj[:, 1]), csv["table_deg"], rtol=0, atol=1e-9)
    for j in range(6):
        assert np.allclose(np.degrees(traj[:, 2 + j]), csv[f"j{j + 1}_deg"], rtol=0, atol=1e-9)


def test_the_cloud_has_the_points_of_cloud_ply_and_lies_on_the_part(light_runs):
    out, plan = light_runs
    with open(out / "cloud.ply", "rb") as f:
        header = f.read(2000).split(b"end_header")[0].decode()
    count = int(next(line.split()[2] for line in header.splitlines()
                     if line.startswith("element vertex")))
    cloud = plan.cloud
    assert cloud.shape == (count, 3) and count > 0
    assert plan.coverage["points"] == count
    # A view of the plan's own buffer, not a copy, and read-only.
    assert not cloud.flags.owndata and not cloud.flags.writeable
    # Every point within the part's bounding box (m), normals unit, incidence in [0, pi/2].
    v = scanplan.load_job(RINGS, overrides=LIGHT).problem().part_vertices
    assert np.all(cloud >= v.min(axis=0) - 1e-3) and np.all(cloud <= v.max(axis=0) + 1e-3)
    assert np.allclose(np.linalg.norm(plan.cloud_normals, axis=1), 1.0, atol=1e-9)
    assert np.all((plan.cloud_incidence >= 0) & (plan.cloud_incidence <= np.pi / 2 + 1e-12))


def test_maps_are_the_plans_buffer_with_their_axes(light_runs):
    _, plan = light_runs
    maps = plan.maps
    assert maps.dtype == np.float32 and not maps.flags.owndata
    assert maps.shape == (len(plan.map_branches), len(plan.map_angles), len(plan.map_times))
    assert np.all((maps >= 0) & (maps <= 1))
    assert plan.branch in plan.map_branches
    assert plan.objective["J"] == pytest.approx(
        plan.objective["f"] + plan.objective["omega"] + plan.objective["alpha"])
    assert plan.validation["valid"] and plan.validation["violations"] == []
    assert plan.scanner_poses.shape == (len(plan.trajectory), 4, 4)


def test_fk_of_every_ik_solution_is_the_pose():
    robot = scanplan.load_robot(SOURCE / "data" / "robots" / "viper_s650.yaml")
    rng = np.random.default_rng(7)
    for _ in range(50):
        q = rng.uniform(robot.lower, robot.upper)
        T = robot.fk(q)
        solutions = robot.ik(T)
        assert solutions.shape[1] == 6 and len(solutions) >= 1
        for s in solutions:
            assert np.allclose(robot.fk(s), T, rtol=0, atol=1e-9)
        # q itself is among them, up to whole turns.
        wrapped = np.angle(np.exp(1j * (solutions - q)))
        assert np.min(np.abs(wrapped).max(axis=1)) < 1e-6
    far = np.eye(4)
    far[:3, 3] = [10.0, 0.0, 0.0]  # 10 m out: no solution
    assert robot.ik(far).shape == (0, 6)


def test_an_input_error_carries_the_command_lines_message(tmp_path):
    bad = {"table.radius_mm": -5}
    run = subprocess.run([BINARY, "path", str(RINGS), "-o", str(tmp_path / "o")] + set_args(bad),
                         capture_output=True, text=True)
    assert run.returncode == 4
    with pytest.raises(scanplan.InputError) as error:
        scanplan.load_job(RINGS, overrides=bad)
    assert run.stderr.strip() == "scanplan: error: " + str(error.value)
    assert isinstance(error.value, ValueError)


def test_bad_input_raises_and_never_crashes(tmp_path):
    garbage = tmp_path / "garbage.yaml"
    garbage.write_bytes(b"\xff\xfe: [\x00")
    for call in (lambda: scanplan.load_job(tmp_path / "missing.yaml"),
                 lambda: scanplan.load_job(garbage),
                 lambda: scanplan.load_job(RINGS, overrides={"planner.method": "nope"}),
                 lambda: scanplan.load_robot(garbage)):
        with pytest.raises(scanplan.InputError):
            call()
    robot = scanplan.load_robot(SOURCE / "data" / "robots" / "viper_s650.yaml")
    for q in ([0.0] * 5, [np.nan] * 6):
        with pytest.raises(scanplan.InputError):
            robot.fk(q)
    with pytest.raises(scanplan.InputError):
        robot.ik(np.full((4, 4), 2.0))  # not a rigid transform
    with pytest.raises((TypeError, RuntimeError)):
        scanplan.load_job(RINGS, overrides=[1, 2])
    problem = scanplan.load_job(RINGS, overrides=dict(LIGHT, **{"simulation.enabled": False}))
    with pytest.raises(scanplan.InputError):
        problem.problem().simulate = True  # the job turned it off


def test_progress_reaches_the_callable_on_this_thread():
    seen = []
    problem = scanplan.load_job(RINGS, overrides=dict(LIGHT, **{"simulation.enabled": False}))
    problem = problem.problem()
    plan = scanplan.plan(problem, planner="dp",
                         progress=lambda stage, f: seen.append((stage, f, threading.get_ident())))
    assert plan.status == "planned"
    assert seen and all(0.0 <= f <= 1.0 for _, f, _ in seen)
    assert {stage for stage, _, _ in seen} <= {"auto", "map"}
    assert all(ident == threading.get_ident() for _, _, ident in seen)


def test_ctrl_c_during_a_long_plan_raises_keyboard_interrupt_within_a_second():
    problem = scanplan.load_job(SOURCE / "data" / "jobs" / "demo.yaml").problem()
    sent = []

    def interrupt():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(1.5, interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        scanplan.plan(problem)
    raised = time.monotonic()
    timer.join()
    assert sent and raised - sent[0] < 1.0


def report_without_timing(path):
    """report.json without its timing fields (every "seconds" and times_s)."""
    def strip(value):
        if isinstance(value, dict):
            return {k: strip(v) for k, v in value.items() if k not in ("seconds", "times_s")}
        if isinstance(value, list):
            return [strip(v) for v in value]
        return value
    return strip(json.loads(path.read_text()))


def files_under(folder):
    return sorted(p.relative_to(folder) for p in folder.rglob("*") if p.is_file())


def test_write_gives_the_command_lines_folder(light_runs, tmp_path):
    out, plan = light_runs
    written = tmp_path / "py"
    summary = plan.write(written)
    assert "wrote      " + str(written) in summary
    assert files_under(written) == files_under(out)
    for name in files_under(out):
        if name.name == "report.json":
            assert report_without_timing(written / name) == report_without_timing(out / name)
        else:
            assert (written / name).read_bytes() == (out / name).read_bytes(), name
    # A folder holding the job's own files is refused, and nothing is written into it.
    before = files_under(RINGS.parent)
    with pytest.raises(scanplan.InputError, match="write\\(dir\\)"):
        plan.write(RINGS.parent)
    assert files_under(RINGS.parent) == before


def write_cube_stl(path, size_mm):
    """An ASCII STL of a cube with its corner at the origin, outward normals."""
    s = size_mm
    corners = np.array([[x, y, z] for x in (0, s) for y in (0, s) for z in (0, s)], float)
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    lines = ["solid cube"]
    for a, b, c, d in faces:
        for tri in ((a, b, c), (a, c, d)):
            p = corners[list(tri)]
            n = np.cross(p[1] - p[0], p[2] - p[0])
            n /= np.linalg.norm(n)
            if np.dot(n, p.mean(axis=0) - s / 2) < 0:  # outward
                p, n = p[::-1], -n
            lines.append("facet normal {} {} {}".format(*n))
            lines.append("outer loop")
            lines += ["vertex {} {} {}".format(*v) for v in p]
            lines += ["endloop", "endfacet"]
    lines.append("endsolid cube")
    path.write_text("\n".join(lines) + "\n")


def test_a_second_setup_turns_the_cube_over_as_the_command_line_does(tmp_path):
    write_cube_stl(tmp_path / "cube.stl", 60)
    cube = {"part.mesh": str(tmp_path / "cube.stl"), "part.place": "table", "scan.paths": "[]",
            "scan.auto": "{point_spacing_mm: 1.0, sample_spacing_mm: 4}", "scan.dt_s": 0.2,
            "map.branch": "RIGHTY ABOVE NOFLIP", "map.angle_step_deg": 4,
            "scanner.rays_per_profile": 80}
    out = tmp_path / "cli"
    run = subprocess.run([BINARY, "plan", str(RINGS), "-o", str(out), "--setups", "2"]
                         + set_args(cube), capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    plan = scanplan.plan(scanplan.load_job(RINGS, overrides=cube).problem(), setups=2)
    assert plan.status == "planned"
    setups = plan.setups
    assert setups["status"] == "planned" and setups["gain"] > 0.1  # the bottom, a sixth
    both = setups["combined"]
    assert both["area_fraction"] >= 0.98
    assert both["area_fraction"] >= plan.coverage["area_fraction"] + 0.1
    p = plan.program  # the moves' time split by the axes whose limits set it
    assert p["moves"] > 0 and p["moves_set_by_axis"].shape == (7,)
    assert 0 < p["moves_set_by_axis"].sum() <= p["moving"] + 1e-9
    second = plan.second_setup
    assert second.status == "planned" and second.validation["valid"]
    assert second.trajectory.shape[1] == 8 and len(second.cloud) > 0
    # The same trajectory as the command line's setup2/trajectory.csv.
    csv = np.genfromtxt(out / "setup2" / "trajectory.csv", delimiter=",", names=True)
    assert np.allclose(second.trajectory[:, 0], csv["t_s"], rtol=0, atol=1e-9)
    assert np.allclose(np.degrees(second.trajectory[:, 2]), csv["j1_deg"], rtol=0, atol=1e-9)
    written = tmp_path / "py"
    plan.write(written)
    assert files_under(written) == files_under(out)
    assert ((written / "setup2" / "trajectory.csv").read_bytes()
            == (out / "setup2" / "trajectory.csv").read_bytes())
    assert report_without_timing(written / "report.json") == report_without_timing(
        out / "report.json")
    with pytest.raises(scanplan.InputError):
        scanplan.plan(scanplan.load_job(RINGS, overrides=cube).problem(), setups=3)


def test_problem_settings_reach_the_plan_and_bad_ones_raise():
    problem = scanplan.load_job(RINGS, overrides=dict(LIGHT, **{"simulation.enabled": False}))
    problem = problem.problem()
    problem.map_angle_step = np.radians(4.0)
    problem.ray_horizon, problem.ray_cost_to_go = 12, False
    problem.k_omega, problem.k_alpha, problem.time_limit = 2.0, 0.0, 30.0
    assert (problem.ray_horizon, problem.ray_cost_to_go, problem.k_omega) == (12, False, 2.0)
    plan = scanplan.plan(problem, planner="ray")
    assert plan.status == "planned"
    assert np.allclose(np.diff(plan.map_angles), np.radians(4.0), rtol=0, atol=1e-12)
    o = plan.objective  # k_alpha = 0: no acceleration term
    assert o["alpha"] == 0.0 and o["J"] == pytest.approx(o["f"] + o["omega"] + o["alpha"])
    for name, value, key in (("ray_horizon", 0, "planning.planners.ray.horizon"),
                             ("k_omega", -1.0, "planning.objective.k_omega"),
                             ("time_limit", float("nan"), "planning.termination.time_limit_s"),
                             ("map_angle_step", 0.0, "map.angle_step")):
        bad = scanplan.load_job(RINGS, overrides=LIGHT).problem()
        setattr(bad, name, value)
        with pytest.raises(scanplan.InputError, match=key.replace(".", "\\.")):
            scanplan.plan(bad)
