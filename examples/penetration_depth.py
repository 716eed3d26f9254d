"""Translational penetration depth with a non-convex obstacle: ``signed_distance`` inside CO.

For a robot R translating at a fixed orientation, the C-obstacle ``CO = O ⊕ (c - R)`` holds
every reference-point position at which the robot touches or overlaps the obstacle O. At a
position q inside CO, ``-signed_distance(q)`` is the distance from q to the boundary of CO:
the length of the shortest translation that separates the robot from the obstacle, i.e. the
translational penetration depth. Outside, ``signed_distance(q)`` is the clearance. The sign
is exact (``contains``); the magnitude is float64.

The obstacle here is a torus (non-convex, genus 1): its C-obstacle is computed exactly by
NCC-CVMS (``cspace.minkowski_sum``), then queried on its closed triangle surface.

Run: ``python examples/penetration_depth.py``
"""

from __future__ import annotations

import numpy as np
import trimesh

import cspace


def main() -> int:
    torus = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3, major_sections=16,
                                   minor_sections=8)
    robot = trimesh.creation.box(extents=(0.2, 0.2, 0.2)).vertices  # a cube, centred at 0
    co = cspace.CSpaceObstacle.build((torus.vertices, torus.faces), robot,
                                     reference_point=(0.0, 0.0, 0.0))
    print(f"C-obstacle: kind {co.kind!r}, {len(co.faces)} triangles, "
          f"bounds {np.round(co.bounds, 3).tolist()}")
    points = {
        "tube centre (deep inside)": (1.0, 0.0, 0.0),
        "inside, near the top": (1.0, 0.0, 0.35),
        "centre of the hole (free)": (0.0, 0.0, 0.0),
        "above the torus (free)": (0.0, 1.0, 0.6),
    }
    q = np.array(list(points.values()))
    d = co.signed_distance(q)
    inside = co.contains(q)
    for (name, p), di, ins in zip(points.items(), d, inside):
        what = f"penetration depth {-di:.4f}" if ins else f"clearance {di:.4f}"
        print(f"{name:28s} q = {p}: {'in collision' if ins else 'free'}, {what}")
    # The depth is a translation that frees the robot: move the deep point straight up by the
    # depth plus a little, and it is out.
    up = q[0] + np.array([0.0, 0.0, -d[0] + 1e-6])
    print(f"tube centre moved up by depth + 1e-6 -> in collision: {co.contains(up)}")
    ok = bool(inside[0] and inside[1] and not inside[2] and not inside[3]
              and (d[inside] < 0).all() and (d[~inside] > 0).all())
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
