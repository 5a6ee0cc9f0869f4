#!/usr/bin/env python3
"""Plan a job and show its simulated cloud in Open3D beside the part, coloured by incidence.

    PYTHONPATH=build/python python3 examples/python/cloud_by_incidence.py
    PYTHONPATH=build/python python3 examples/python/cloud_by_incidence.py --image cloud.png \\
        --ply cloud_incidence.ply      # no window: a picture and a coloured PLY

Blue points were seen head-on, red ones at the steepest incidence the scan allows. The part is
drawn beside the cloud (shifted along x by 1.2 of its width) so the uncovered faces show.
"""
import argparse
import pathlib

import matplotlib
import numpy as np
import open3d as o3d

import scanplan

REPO = pathlib.Path(__file__).resolve().parents[2]


def coloured_cloud(plan):
    """The plan's cloud as an Open3D point cloud (m), coloured by incidence (turbo colour map)."""
    incidence = np.degrees(plan.cloud_incidence)
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(plan.cloud))
    cloud.normals = o3d.utility.Vector3dVector(plan.cloud_normals)
    shade = np.clip(incidence / max(incidence.max(), 1e-9), 0.0, 1.0)
    cloud.colors = o3d.utility.Vector3dVector(matplotlib.colormaps["turbo"](shade)[:, :3])
    return cloud, incidence


def part_mesh(problem, shift):
    """The part's mesh (m), grey, moved by `shift`."""
    mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(problem.part_vertices + shift),
                                     o3d.utility.Vector3iVector(problem.part_triangles.copy()))
    mesh.compute_vertex_normals()
    mesh.paint_uniform_color([0.7, 0.7, 0.7])
    return mesh


def save_image(geometries, path):
    """Renders `geometries` without a window (needs an X display, e.g. xvfb-run) into `path`."""
    vis = o3d.visualization.Visualizer()
    vis.create_window(visible=False, width=1024, height=768)
    for g in geometries:
        vis.add_geometry(g)
    view = vis.get_view_control()
    view.set_front([0.4, -1.0, 0.6])
    view.set_up([0.0, 0.0, 1.0])
    view.set_zoom(0.7)
    vis.poll_events()
    vis.update_renderer()
    vis.capture_screen_image(str(path), do_render=True)
    vis.destroy_window()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("job", nargs="?", default=REPO / "data" / "jobs" / "demo_rings.yaml")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a job override, as `scanplan plan --set`")
    parser.add_argument("--image", help="render into this PNG instead of opening a window")
    parser.add_argument("--ply", help="also write the coloured cloud to this PLY")
    args = parser.parse_args()

    problem = scanplan.load_job(args.job, overrides=args.set).problem()
    plan = scanplan.plan(problem)
    if plan.cloud is None:
        raise SystemExit(f"no cloud: the plan is {plan.status} ({plan.reason or 'no simulation'})")
    cloud, incidence = coloured_cloud(plan)
    v = problem.part_vertices
    shift = np.array([1.2 * (v[:, 0].max() - v[:, 0].min()), 0.0, 0.0])
    print(f"{len(plan.cloud)} points, incidence {incidence.min():.1f}-{incidence.max():.1f} deg "
          f"(median {np.median(incidence):.1f}); {100 * plan.coverage['area_fraction']:.1f} % "
          f"of the part's area covered")
    if args.ply:
        o3d.io.write_point_cloud(args.ply, cloud)
        print(f"wrote {args.ply}")
    geometries = [cloud, part_mesh(problem, shift)]
    if args.image:
        save_image(geometries, args.image)
        print(f"wrote {args.image}")
    else:
        o3d.visualization.draw_geometries(geometries, window_name=f"{plan.status}: cloud by "
                                          "incidence (blue head-on, red steep) and the part")


if __name__ == "__main__":
    main()
