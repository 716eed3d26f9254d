"""Draw a convex robot, a convex obstacle, their C-obstacle and a path in meshcat (offline HTML).

The scene of ``examples/convex_sum.py``: O is a rotated box, R an ellipsoid-like hull with
reference point c = (0.1, 0, 0), and CO = O ⊕ (−(R − c)) is computed exactly with CVMS. A path
of the reference point bends around CO (every sample checked outside CO); the robot is
animated along it. Open the HTML in any browser, no network needed; "Open Controls" → Scene
toggles each part, → Animations replays the motion. ``--screenshot`` renders a still (robot
parked at a waypoint, animation paused) with headless Chromium: docs/convex_demo.png is one.

Run: ``python examples/view_convex.py [--out out/convex_demo.html]
[--screenshot docs/convex_demo.png]``
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

import cspace
from cspace.viz.scene_view import SceneView
from cspace.viz.browser import screenshot

REFERENCE = np.array([0.1, 0.0, 0.0])  # the robot's reference point, in its own frame
PATH = np.array([
    [-2.2, 0.6, 0.3],
    [-1.6, -1.5, 0.6],
    [0.0, -1.9, 0.7],
    [1.6, -1.5, 0.6],
    [2.2, 0.6, 0.3],
])


def demo_scene():
    """(O, R, CO, path): the obstacle, the robot, the C-obstacle and a free path."""
    rng = np.random.default_rng(1)
    rot = trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3]
    obstacle_pts = trimesh.creation.box((2.0, 1.0, 0.5)).vertices @ rot.T
    sphere = trimesh.creation.icosphere(subdivisions=1, radius=0.3).vertices
    robot_pts = sphere * [1.0, 0.6, 1.4] + REFERENCE
    grid = cspace.Grid.for_points(obstacle_pts, robot_pts)
    O = cspace.ConvexPolytope.from_points(obstacle_pts, grid=grid, name="box")
    R = cspace.ConvexPolytope.from_points(robot_pts, grid=grid, name="robot")
    CO = cspace.convex_minkowski_sum(O, R.reflected(REFERENCE))
    return O, R, CO, PATH


def outside_convex(vertices: np.ndarray, faces: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(k,) bool: points strictly outside a convex polytope, faces wound outward (float check)."""
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    n = np.cross(b - a, c - a)
    side = points @ n.T - (n * a).sum(axis=1)
    return (side > 1e-9 * np.abs(n).sum(axis=1)).any(axis=1)


def build_view(O, R, CO, path, *, play: bool = True, robot_at: int = 0) -> SceneView:
    """The scene; the robot starts at waypoint ``robot_at`` (the animation starts at 0)."""
    view = SceneView()
    view.add_obstacle("box", O.vertices, O.faces)
    view.add_cobstacle("box", CO.vertices, CO.faces)
    view.add_path("free", path)
    view.add_robot("robot", R.vertices, R.faces, path[robot_at], reference=REFERENCE)
    view.animate_robot("robot", path, seconds_per_segment=1.0, play=play)
    view.frame()
    return view


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out/convex_demo.html"),
                    help="HTML file to write (default out/convex_demo.html)")
    ap.add_argument("--screenshot", type=Path, default=None, metavar="PNG",
                    help="also render a still of the scene to this PNG with headless Chromium "
                         "(animation paused, robot at waypoint --robot-at)")
    ap.add_argument("--robot-at", type=int, default=2, help="waypoint of the robot in the still")
    ap.add_argument("--no-play", action="store_true", help="do not start the animation on load")
    args = ap.parse_args()
    if not 0 <= args.robot_at < len(PATH):
        ap.error(f"--robot-at must be a waypoint index in [0, {len(PATH) - 1}]")

    O, R, CO, path = demo_scene()
    dense = np.vstack([np.linspace(path[i], path[i + 1], 200) for i in range(len(path) - 1)])
    if not outside_convex(CO.vertices, CO.faces, dense).all():
        raise SystemExit("demo path enters the C-obstacle")
    counts = {name: int((CO.kind == k).sum()) for k, name in enumerate(cspace.FACET_KINDS)}
    print(f"CO: {CO.polytope.n_facets} facets {counts}; "
          f"the path of {len(path)} waypoints stays outside it")

    view = build_view(O, R, CO, path, play=not args.no_play)
    out = view.save(args.out)
    print(f"wrote {out} ({out.stat().st_size / 1e6:.2f} MB, self-contained; open it in a browser)")
    if args.screenshot is not None:
        # A still, so the picture does not depend on how far the animation got.
        still = build_view(O, R, CO, path, play=False, robot_at=args.robot_at)
        t = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            png = screenshot(still.save(Path(tmp) / "still.html"), args.screenshot)
        print(f"wrote {png} ({time.perf_counter() - t:.1f} s with headless Chromium)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
