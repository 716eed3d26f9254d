"""Plan in a scene file with OMPL and exact C-space checks; re-check the path with FCL.

1. ``model_scene`` decides, per obstacle body, what to build and why (convex, solid, surface
   or dropped) and builds the C-obstacles through the disk cache (``~/.cache/cspace``, or
   ``$CSPACE_CACHE``): a second run loads them.
2. ``plan`` solves with RRTConnect using the exact validity checker and motion validator, and
   re-proves the returned path exactly.
3. FCL re-checks the path, sampled every 1e-3 of the scene size.
4. The path and an offline HTML drawing go to ``out/``.

Run: ``python examples/plan_in_scene.py [SCENE] [SECONDS]`` (default ``scenes/comb.toml``, 2 s).
The narrow scenes (window, cavity, maze) rarely solve in a few seconds with uniform sampling:
the example then writes OMPL's approximate path, which is still collision-free.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import cspace
from cspace.check.cross_check import path_collisions
from cspace.scene.model import model_scene
from cspace.planning.plan import plan
from cspace.planning.ompl_plugin import verify_path
from cspace.viz.draw import draw_scene
from cspace.viz.scene_view import SceneView

ROOT = Path(__file__).resolve().parents[1]


def main(scene_file: str, seconds: float) -> int:
    scene = cspace.load_scene(scene_file)
    model = model_scene(scene, cache=True)
    print(model.explain())
    cs = model.cspace()
    r = plan(cs, scene.start, scene.goal, bounds=scene.bounds, planner="RRTConnect", seed=1,
             time=seconds)
    print(f"status: {r.status}; solved (exact and re-proved): {r.solved}; "
          f"{r.n_states} states, length {r.length:.3f}; {r.time:.2f} s "
          f"({r.state_checks} state checks, {r.motion_checks} exact motion checks)")
    if not len(r.path):
        print("no path returned")
        return 1
    valid = verify_path(cs, r.path, scene.bounds)["valid"]
    bad, n_samples = path_collisions(scene, r.path)  # FCL on the raw scene meshes as loaded
    print(f"exact re-check: valid={valid}; FCL re-check: {len(bad)} colliding of {n_samples} "
          "samples")
    out = ROOT / "out"
    out.mkdir(exist_ok=True)
    np.savetxt(out / f"{scene.name}_path.txt", r.path)
    view = SceneView()
    draw_scene(view, scene, path=r.path)
    view.save(out / f"{scene.name}_plan.html")
    view.close()
    print(f"wrote {out / (scene.name + '_path.txt')} and {out / (scene.name + '_plan.html')}")
    return 0 if valid and not len(bad) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "scenes" / "comb.toml"),
                  float(sys.argv[2]) if len(sys.argv) > 2 else 2.0))
