"""Plan a robot that must turn: a piano through a doorway narrower than it is long.

1. ``plan(scene, slices=8)`` plans over 8 yaw orientations: translations within one
   orientation and turns in place between neighbouring ones, each certified exactly (the
   C-obstacles of the robot at that orientation, or of the hull it sweeps while turning).
   Orientations and turns are built only when the planner comes near an obstacle in them.
2. FCL re-checks the returned path along its continuous motions: 10^3 poses per metre of
   translation and per degree of turning.
3. The path goes to ``out/piano.path`` in OMPL.app's format (``x y z qx qy qz qw``).

Run: ``python examples/plan_with_turns.py [SCENE] [SLICES]`` (default ``scenes/piano.toml``, 8).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import cspace
from cspace.check.cross_check import pose_path_collisions
from cspace.planning.plan import plan

ROOT = Path(__file__).resolve().parents[1]


def main(scene_file: str, slices: int) -> int:
    scene = cspace.load_scene(scene_file)
    fixed = plan(scene, time=1.0, seed=1, turns=False)  # the start orientation only
    print(f"without turning: solved {fixed.solved} ({fixed.status})")
    r = plan(scene, slices=slices, time=10.0, seed=1, cache=True)
    turns = int((np.diff(r.slices) != 0).sum())
    print(f"with {slices} orientations: solved {r.solved}; {len(r.path)} waypoints, {turns} "
          f"turns in place; built {r.built['slices']} of {r.built['of'][0]} orientations and "
          f"{r.built['turns']} of {r.built['of'][1]} turns; {r.time:.2f} s")
    if not r.solved:
        return 1
    # the rotations relative to the start orientation, as the scene's robot is given
    rel = Rotation.from_quat(r.orientations).as_matrix() @ np.asarray(scene.start_rotation).T
    bad, n = pose_path_collisions(scene, r.path, rel, per_metre=1e3, per_degree=1e3)
    print(f"FCL re-check along translations and turns: {bad} colliding of {n} poses")
    out = ROOT / "out"
    out.mkdir(exist_ok=True)
    rows = np.hstack([r.path, r.orientations]) + 0.0
    (out / f"{scene.name}.path").write_text(
        "".join(" ".join(repr(float(x)) for x in row) + "\n" for row in rows))
    print(f"wrote {out / (scene.name + '.path')}")
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "scenes" / "piano.toml"),
                  int(sys.argv[2]) if len(sys.argv) > 2 else 8))
