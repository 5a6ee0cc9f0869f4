#!/usr/bin/env python3
"""Writes the URDF of a scanplan robot file (DH table and primitive link shapes), the way
ROS-Industrial support packages lay them out: every link frame parallel to the base at the zero
pose, on its joint's axis, the axes written as unit vectors (a joint that turns against its DH z
axis, `direction: -1`, gets a negative one), and `tool0` at the flange (z out of it).

    python3 data/robots/urdf/make_urdf.py data/robots/viper_s650.yaml data/robots/urdf/viper_s650.urdf

Capsules, which URDF lacks, become a cylinder and a sphere at each end (the same solid). The
shapes are the robot file's authored primitives, not vendor meshes. Plain Python (math, yaml):
the same input gives the same bytes."""

import math
import sys

import yaml


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def inverse(t):
    r = [[t[j][i] for j in range(3)] for i in range(3)]
    p = [-sum(r[i][k] * t[k][3] for k in range(3)) for i in range(3)]
    return [r[0] + [p[0]], r[1] + [p[1]], r[2] + [p[2]], [0.0, 0.0, 0.0, 1.0]]


def translation(x, y, z):
    return [[1.0, 0.0, 0.0, x], [0.0, 1.0, 0.0, y], [0.0, 0.0, 1.0, z], [0.0, 0.0, 0.0, 1.0]]


def rpy_matrix(r, p, y):
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr, 0.0],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr, 0.0],
            [-sp, cp * sr, cp * cr, 0.0], [0.0, 0.0, 0.0, 1.0]]


def rpy_of(t):
    pitch = math.atan2(-t[2][0], math.hypot(t[0][0], t[1][0]))
    if math.hypot(t[0][0], t[1][0]) < 1e-12:
        return math.atan2(-t[1][2], t[1][1]), pitch, 0.0
    return math.atan2(t[2][1], t[2][2]), pitch, math.atan2(t[1][0], t[0][0])


def dh(row):
    """The DH transform of a row at q = 0, metres."""
    theta = math.radians(row.get("theta_offset_deg", 0.0))
    alpha = math.radians(row["alpha_deg"])
    a, d = row["a_mm"] / 1000.0, row["d_mm"] / 1000.0
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0]]


def num(v):
    v = 0.0 if abs(v) < 1e-12 else v
    return repr(round(v, 12))


def vec(values):
    return " ".join(num(v) for v in values)


def origin(t):
    return f'<origin xyz="{vec([t[0][3], t[1][3], t[2][3]])}" rpy="{vec(rpy_of(t))}"/>'


def from_to_frame(a, b):
    """The frame at the midpoint of a → b with z along it, and the length."""
    d = [b[i] - a[i] for i in range(3)]
    length = math.sqrt(sum(c * c for c in d))
    z = [c / length for c in d]
    helper = [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0]
    x = [helper[1] * z[2] - helper[2] * z[1], helper[2] * z[0] - helper[0] * z[2],
         helper[0] * z[1] - helper[1] * z[0]]
    n = math.sqrt(sum(c * c for c in x))
    x = [c / n for c in x]
    y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]]
    m = [(a[i] + b[i]) / 2.0 for i in range(3)]
    return [[x[0], y[0], z[0], m[0]], [x[1], y[1], z[1], m[1]], [x[2], y[2], z[2], m[2]],
            [0.0, 0.0, 0.0, 1.0]], length


def shape_pose(shape):
    """The shape's frame in its DH frame (mm → m) and its length along z, if it has one."""
    if "from_mm" in shape:
        a = [v / 1000.0 for v in shape["from_mm"]]
        b = [v / 1000.0 for v in shape["to_mm"]]
        if a == b:
            return translation(*a), 0.0
        return from_to_frame(a, b)
    pose = shape.get("pose", {})
    xyz = [v / 1000.0 for v in pose.get("xyz_mm", [0, 0, 0])]
    rpy = [math.radians(v) for v in pose.get("rpy_deg", [0, 0, 0])]
    t = rpy_matrix(*rpy)
    for i in range(3):
        t[i][3] = xyz[i]
    return t, shape.get("length_mm", 0.0) / 1000.0


def collisions(shape, X_LD):
    """<collision> elements of one robot-file shape, in the URDF link frame."""
    t, length = shape_pose(shape)
    t = matmul(X_LD, t)
    kind = shape["type"]
    r = shape.get("radius_mm", 0.0) / 1000.0
    if kind == "box":
        size = vec([v / 1000.0 for v in shape["size_mm"]])
        return [f'<collision>{origin(t)}<geometry><box size="{size}"/></geometry></collision>']
    if kind == "sphere":
        return [f'<collision>{origin(t)}<geometry><sphere radius="{num(r)}"/></geometry></collision>']
    out = []
    if length > 0.0:
        out.append(f'<collision>{origin(t)}<geometry><cylinder radius="{num(r)}" '
                   f'length="{num(length)}"/></geometry></collision>')
    if kind == "capsule":
        for end in (-length / 2.0, length / 2.0):
            c = matmul(t, translation(0.0, 0.0, end))
            out.append(f'<collision>{origin(c)}<geometry><sphere radius="{num(r)}"/></geometry>'
                       '</collision>')
    return out


def main(robot_file, out_file):
    with open(robot_file) as f:
        robot = yaml.safe_load(f)
    frames = [translation(0.0, 0.0, 0.0)]  # DH frames at q = 0
    for row in robot["dh"]:
        frames.append(matmul(frames[-1], dh(row)))
    # Link k (k = 1 … 6) sits on joint k's axis (the origin of DH frame k − 1), base-aligned.
    link_frames = [translation(0.0, 0.0, 0.0)] + [
        translation(frames[k][0][3], frames[k][1][3], frames[k][2][3]) for k in range(6)]
    name = "".join(c if c.isalnum() else "_" for c in robot["name"].lower())
    lines = [f'<?xml version="1.0"?>',
             f'<!-- {robot["name"]}: written by data/robots/urdf/make_urdf.py from '
             f'{robot_file.split("/")[-1]} (its DH table, limits and speeds).',
             '     Collision geometry: the robot file\'s authored primitives (capsules as a cylinder '
             'and two spheres), not vendor meshes. -->',
             f'<robot name="{name}">']
    links = ["base_link"] + [f"link_{k}" for k in range(1, 7)]
    for k, link in enumerate(links):
        X_LD = matmul(inverse(link_frames[k]), frames[k])
        shapes = (robot.get("links") or [{}] * 7)[k].get("shapes", [])
        body = [c for s in shapes for c in collisions(s, X_LD)]
        lines.append(f'  <link name="{link}">' + "".join("\n    " + c for c in body) +
                     ("\n  </link>" if body else "</link>"))
    lines.append('  <link name="tool0"/>')
    for k in range(1, 7):
        row = robot["dh"][k - 1]
        z = [frames[k - 1][i][2] * row.get("direction", 1) for i in range(3)]
        t = matmul(inverse(link_frames[k - 1]), link_frames[k])
        lines.append(f'  <joint name="joint_{k}" type="revolute">\n'
                     f'    <parent link="{links[k - 1]}"/><child link="{links[k]}"/>\n'
                     f'    {origin(t)}\n    <axis xyz="{vec(z)}"/>\n'
                     f'    <limit lower="{num(math.radians(row["min_deg"]))}" '
                     f'upper="{num(math.radians(row["max_deg"]))}" effort="0" '
                     f'velocity="{num(math.radians(row["max_speed_deg_s"]))}"/>\n  </joint>')
    lines.append('  <joint name="joint_6-tool0" type="fixed">\n'
                 '    <parent link="link_6"/><child link="tool0"/>\n'
                 f'    {origin(matmul(inverse(link_frames[6]), frames[6]))}\n  </joint>')
    lines.append("</robot>\n")
    with open(out_file, "w") as f:
        f.write("\n".join(lines))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
