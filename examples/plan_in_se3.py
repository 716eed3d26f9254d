"""Plan a robot that turns while it moves: a plate through a tunnel it fits only on edge.

1. ``plan(scene, planner='auto')``, what ``cspace plan`` runs: at the start's orientation no
   translation passes (proved); the robot then turns in SE(3), every pose and every motion
   certified by clearance (a motion is free when the clearances at its ends add up to more
   than the farthest any robot point moves, halving it until they do).
2. FCL re-checks the returned path along its continuous motions (translation and turning
   together): 10^3 poses per scene size and 10^2 per degree.
3. The path goes to ``out/plate.path`` in OMPL.app's format (``x y z qx qy qz qw``) and an
   animation of the turning robot to ``out/plate.html``.

Run: ``python examples/plan_in_se3.py [SCENE]`` (default ``scenes/plate.toml``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import cspace
from cspace import viz
from cspace.check.cross_check import pose_path_collisions
from cspace.planning.plan import plan

ROOT = Path(__file__).resolve().parents[1]


def main(scene_file: str) -> int:
    scene = cspace.load_scene(scene_file)
    r = plan(scene, planner="auto", time=60.0, seed=1)
    for t in r.tried:
        print(f"  tried {t['planner']}{' in SE(3)' if t.get('space') else ''}: "
              f"{t.get('answer') or ('solved' if t['solved'] else 'no path')} in "
              f"{t['seconds']:.2f} s")
    print(f"solved {r.solved} by {r.planner} in {r.time:.2f} s; {len(r.path)} poses")
    if not r.solved:
        return 1
    c = r.certified
    print(f"certified: {c['motions']} motions, {c['queries']} clearance queries, bisection depth "
          f"up to {c['max_depth']}, error bound {c['error_bound']:.3g}")
    # rotations relative to the start orientation (the scene's robot already has it)
    rel = (Rotation.from_quat(r.orientations)
           * Rotation.from_matrix(scene.start_rotation).inv()).as_matrix()
    size = float(np.ptp(scene.bounds, axis=0).max())
    bad, n = pose_path_collisions(scene, r.path, rel, per_metre=1e3 / size, per_degree=100)
    print(f"FCL re-check along the motions: {bad} colliding of {n} poses")
    out = Path("out")
    out.mkdir(exist_ok=True)
    rows = np.hstack([r.path, r.orientations]) + 0.0
    (out / "plate.path").write_text("".join(" ".join(repr(float(x)) for x in row) + "\n"
                                            for row in rows))
    view = viz.SceneView()
    viz.draw_scene(view, scene, path=r.path, rotations=rel, cobstacles=False)
    view.save(out / "plate.html")
    print(f"wrote {out / 'plate.path'} and {out / 'plate.html'}")
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "scenes" / "plate.toml")))
