# Type stubs of the compiled module `scanplan` (python/*.cpp). Units: m, rad, s throughout.
from os import PathLike
from typing import Callable, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

class InputError(ValueError):
    """Bad input: the message names the file, the key, the value and what was expected."""

class Job:
    name: str
    source: PathLike
    def problem(self) -> Problem: ...

class Problem:
    name: str
    planner: str  # 'ray' | 'dp' | 'ompl'
    refine: bool
    validate: bool
    simulate: bool
    auto_scan: bool
    part_vertices: npt.NDArray[np.float64]  # (V, 3), part frame, m
    part_triangles: npt.NDArray[np.int32]  # (F, 3)

class Plan:
    status: str  # 'planned' | 'no_path' | 'no_executable_path' | 'invalid_trajectory'
    reason: str
    planned: bool
    branch: Optional[str]
    objective: dict  # J, f, omega, alpha (s), min_f, max_abs_omega (rad/s), max_abs_alpha (rad/s^2)
    dp_gap: Optional[float]
    validation: Optional[dict]
    coverage: Optional[dict]
    program: dict  # total, scanning, moving (s), moves, backed_off_moves, passes_table_held, table_held_J (s), moves_set_by_axis (7,) s
    trajectory: Optional[npt.NDArray[np.float64]]  # (N, 8): t, table, j1..j6 (s, rad)
    scanner_poses: Optional[npt.NDArray[np.float64]]  # (N, 4, 4), part frame, m
    maps: npt.NDArray[np.float32]  # (branches, angles, samples)
    map_angles: npt.NDArray[np.float64]  # (angles,), rad
    map_times: npt.NDArray[np.float64]  # (samples,), s
    map_branches: list
    cloud: Optional[npt.NDArray[np.float64]]  # (M, 3), part frame, m
    cloud_normals: Optional[npt.NDArray[np.float64]]  # (M, 3)
    cloud_incidence: Optional[npt.NDArray[np.float64]]  # (M,), rad
    cloud_times: Optional[npt.NDArray[np.float64]]  # (M,), s
    setups: Optional[dict]  # with setups=2: turn, gain, status, combined
    second_setup: Optional[Plan]  # with setups=2: the second setup's plan
    def write(self, dir: Union[str, PathLike]) -> str: ...  # the files of `plan -o DIR`

class Robot:
    name: str
    lower: npt.NDArray[np.float64]  # (6,), rad
    upper: npt.NDArray[np.float64]  # (6,), rad
    max_speed: npt.NDArray[np.float64]  # (6,), rad/s
    def fk(self, q: npt.ArrayLike) -> npt.NDArray[np.float64]: ...  # (4, 4), base frame, m
    def ik(self, T: npt.ArrayLike, within_limits: bool = False) -> npt.NDArray[np.float64]: ...  # (k, 6)
    def branch_of(self, q: npt.ArrayLike) -> str: ...

def load_job(path: Union[str, PathLike],
             overrides: Union[None, Mapping[str, object], Sequence[str]] = None) -> Job: ...
def load_robot(path: Union[str, PathLike]) -> Robot: ...
def plan(problem: Problem, planner: Optional[str] = None,
         progress: Optional[Callable[[str, float], None]] = None,
         compare: bool = False, setups: int = 1) -> Plan: ...
