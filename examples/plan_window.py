"""Plan through the thin window (scenes/window.toml) with OMPL and exact C-space checks.

Plans with RRTConnect (seeded) using the exact validity checker and motion validator of
:mod:`cspace.ompl_plugin`, re-checks the returned path exactly (``segment_free``) and with FCL
sampled every 1e-3 of the scene size, then writes ``out/window_path.txt`` (n x 3) and
``out/window_plan.html``.

The window's free passage is 0.01 wider than the robot (2% clearance) in a 0.05-thick wall:
with OMPL's uniform sampling RRTConnect may not get through within the budget. The example
then says so and writes the approximate (still collision-free) path it got.

Run: ``python examples/plan_window.py [seconds]`` (default 20).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import cspace
from cspace.fcl_check import FclOracle
from cspace.ompl_plugin import plan, verify_path
from cspace.viz import SceneView, draw_scene

ROOT = Path(__file__).resolve().parents[1]


def fcl_collisions(cs: cspace.CSpace, P: np.ndarray) -> int:
    """Samples along the path (step 1e-3 of the scene size) where FCL finds a collision."""
    lo, hi = cs.bounds
    step = 1e-3 * float(np.linalg.norm(hi - lo))
    parts = [P[:1]]
    for a, b in zip(P[:-1], P[1:]):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        parts.append(a + (np.arange(1, n + 1)[:, None] / n) * (b - a))
    Q = np.vstack(parts)
    hit = np.zeros(len(Q), dtype=bool)
    for o in cs.obstacles:
        orc = FclOracle(o.obstacle.vertices, o.obstacle.faces, o.robot.vertices, o.robot.faces,
                        o.reference_point, convex=True)
        blo, bhi = o.bounds
        near = np.nonzero(((blo <= Q) & (Q <= bhi)).all(axis=1))[0]
        if near.size:
            hit[near] |= orc.collides(Q[near])
    return int(hit.sum()), len(Q)


def main(seconds: float = 20.0) -> int:
    scene = cspace.load_scene(ROOT / "scenes" / "window.toml")
    cs = cspace.CSpace.from_scene(scene)
    r = plan(scene, planner="RRTConnect", seed=1, time=seconds)
    print(f"scene {scene.name}: {len(cs)} C-obstacles; RRTConnect, {seconds:g} s budget")
    print(f"status: {r.status}; solved (exact and re-proved): {r.solved}; "
          f"{r.n_states} states, length {r.length:.3f}; {r.time:.2f} s "
          f"({r.state_checks} state checks, {r.motion_checks} exact motion checks)")
    if not len(r.path):
        print("no path returned")
        return 1
    report = verify_path(cs, r.path)
    n_hit, n_samples = fcl_collisions(cs, r.path)
    print(f"exact re-check: valid={report['valid']}; FCL re-check: {n_hit} colliding of "
          f"{n_samples} samples")
    out = ROOT / "out"
    out.mkdir(exist_ok=True)
    np.savetxt(out / "window_path.txt", r.path)
    view = SceneView()
    draw_scene(view, scene, path=r.path)
    view.save(out / "window_plan.html")
    view.close()
    print(f"wrote {out / 'window_path.txt'} and {out / 'window_plan.html'}")
    if not r.solved:
        print("not solved within the budget: the path above is OMPL's approximate solution "
              "(collision-free, does not reach the goal)")
    return 0 if report["valid"] and n_hit == 0 else 1


if __name__ == "__main__":
    sys.exit(main(float(sys.argv[1]) if len(sys.argv) > 1 else 20.0))
