"""A path, or a proof that none exists: the decision on two shipped scenes.

- ``scenes/cage.toml``: a cube shut in a cage whose only opening is a slot half its width.
  :func:`cspace.planning.decide.decide` proves that no translation path exists: start and goal
  are in different components of the exact free space (:mod:`cspace.planning.free_space`); the
  page is a cutaway (the lower half) of the cage and of the proof, the closed surface of the
  C-obstacles' union around the start's component, that shuts the robot in.
- ``scenes/comb.toml``: the same decision finds a path through free cells, between the teeth
  (every segment then proved by ``segment_free``); the page shows it.

Run: ``python examples/decide_scenes.py [--out out] [--screenshot docs]`` (``--screenshot``
also renders ``decide_cage.png`` and ``decide_comb.png`` there with headless Chromium).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cspace
from cspace.planning.decide import decide
from cspace.viz.browser import screenshot
from cspace.viz.draw import draw_scene
from cspace.viz.scene_view import SceneView

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def _below(V, F, z0):
    """The triangles ``V[F]`` clipped to ``z <= z0`` (each clipped polygon fanned)."""
    import numpy as np

    out = []
    for tri in V[F]:
        poly = []
        for a, b in zip(tri, np.roll(tri, -1, axis=0)):
            if a[2] <= z0:
                poly.append(a)
            if (a[2] - z0) * (b[2] - z0) < 0:
                poly.append(a + (z0 - a[2]) / (b[2] - a[2]) * (b - a))
        out += [(poly[0], poly[k], poly[k + 1]) for k in range(1, len(poly) - 1)]
    P = np.array(out, dtype=np.float64).reshape(-1, 3)
    return P, np.arange(len(P)).reshape(-1, 3)


def draw_cut(view: SceneView, scene, d) -> None:
    """The lower half (below the start) of the obstacles and of the proof (its separating
    surface, or its wall of cells), the robot at start and goal: a cutaway that shows the
    robot shut in."""
    import numpy as np
    import trimesh

    for body in scene.obstacles:  # the cage's walls are boxes: cut each at the start's z
        lo, hi = body.vertices.min(axis=0), body.vertices.max(axis=0)
        hi[2] = min(hi[2], scene.start[2])
        if hi[2] > lo[2]:
            m = trimesh.creation.box(bounds=[lo, hi])
            view.add_obstacle(body.name, m.vertices, m.faces)
    wall = d.to_trimesh("blocked")
    if d.separation is not None:  # one closed surface: cut by the plane, both sides drawn
        V, F = _below(np.asarray(wall.vertices), np.asarray(wall.faces), scene.start[2])
        wall = trimesh.Trimesh(V, np.vstack([F, F[:, ::-1]]), process=False)
    else:  # boxes of cells: those below the plane
        keep = wall.triangles_center[:, 2] <= scene.start[2]
        wall = trimesh.Trimesh(wall.vertices, wall.faces[keep], process=False)
    view.add_cells("wall", wall.vertices, wall.faces, opacity=0.3)
    for end in ("start", "goal"):
        view.add_robot(end, scene.robot.vertices, scene.robot.faces, getattr(scene, end),
                       reference=scene.reference_point)
    view.frame(direction=np.array([0.4, -1.0, 1.3]))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out"), help="folder of the HTML pages")
    ap.add_argument("--screenshot", type=Path, default=None, metavar="DIR",
                    help="also render each page to a PNG in this folder")
    args = ap.parse_args()
    for name in ("cage", "comb"):
        scene = cspace.load_scene(SCENES / f"{name}.toml")
        cs = cspace.model_scene(scene).cspace()
        d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=10.0)
        print(f"{name}: {d.answer} ({d.reason}) in {d.time:.2f} s")
        view = SceneView()
        if d.answer == "no path":
            draw_cut(view, scene, d)
        else:
            draw_scene(view, scene, path=d.path, animate=False, cobstacles=False)
        html = view.save(args.out / f"decide_{name}.html")
        print(f"wrote {html}")
        if args.screenshot is not None:
            print(f"wrote {screenshot(html, args.screenshot / f'decide_{name}.png')}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
