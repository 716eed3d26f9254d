"""The robot turns while it moves (issue #50): cspace's default planner against OMPL.app's way.

Per problem and seed, same machine, same run, same budget:

- **cspace**: ``plan(scene, planner='auto')``, what ``cspace plan X --time T`` runs: every pose
  and motion certified by clearance (SE(3)), or translations proved exactly;
- **OMPL.app's way**: ``plan_sampled`` (RRTConnect in SE(3), FCL on the raw meshes at each state,
  OMPL's discrete motion validation at resolution 0.01: nothing proved between states).

Every returned path is re-checked by cspace's FCL oracle along its continuous motions
(``pose_path_collisions``: 10^3 poses per scene size and 10^2 per degree): the colliding poses
are reported for both. Also: the clearance query (``MeshClearance``) against FCL's distance on
the same raw meshes, at poses near each problem's start.

Problems: the shipped plate (a tunnel passed only on edge) and piano (its goal turned 90
degrees), the plate turned, scaled and moved to (250, 150, -300); OMPL.app-style Collada
problems (tests/real_problems.py): the slot wall (a T through a slot at the goal's
orientation) and the twisting corner (hallways 22 and 18: the T turns as it moves round the
corner; an apartment-class world whose doors the piano passes only turned); the Parasol
alpha puzzle and bug trap with their own queries.

Writes the section between the markers in ``benchmarks/reports/planning.md``. Run:
``python benchmarks/bench_se3.py [--time 30] [--seeds 1 2]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import cspace  # noqa: E402
from cspace.check.cross_check import pose_path_collisions  # noqa: E402
from cspace.planning.plan import plan  # noqa: E402
from cspace.planning.sampled import plan_sampled  # noqa: E402

BEGIN = "<!-- bench_se3: begin -->"
END = "<!-- bench_se3: end -->"
DATA = ROOT.parent / "shared" / "data" / "parasol_open_ppl_env"


def problems(tmp: Path) -> dict:
    import real_problems as rp
    from metamorphic import GRID_MOVES
    from test_se3 import _generate, moved

    out = {}
    out["plate (shipped)"] = cspace.load_scene(ROOT / "scenes" / "plate.toml")
    piano = cspace.load_scene(ROOT / "scenes" / "piano.toml")
    G = Rotation.from_euler("z", 90, degrees=True).as_matrix()
    out["piano, goal turned 90 deg"] = dataclasses.replace(piano, goal_rotation=G)
    (tmp / "plate").mkdir()
    (tmp / "plate" / "plate.toml").write_text(_generate().plate(half=9.0))
    out["plate turned, x3.7, at (250, 150, -300)"] = moved(
        cspace.load_scene(tmp / "plate" / "plate.toml"), GRID_MOVES[4])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out["slot wall (Collada, T robot)"] = cspace.load_scene(
            rp.slot_wall(tmp / "slot", wall="boxes").cfg)
        for w in (22.0, 18.0):
            out[f"twisting corner, hallway {w:g} (Collada, 15k triangles)"] = cspace.load_scene(
                rp.twisting_corner(tmp / f"corner{w:g}", width=w).cfg)
        out["apartment, doors 40 (Collada, 40k triangles, piano)"] = cspace.load_scene(
            rp.apartment(tmp / "apartment", door=40.0).cfg)
        if DATA.is_dir():
            out["Parasol alpha 1.6"] = cspace.load_scene(DATA / "alpha1.6" / "alpha.query")
            out["Parasol bug trap"] = cspace.load_scene(DATA / "bug_trap1.0" / "bug-trap.query")
    return out


def _colliding(scene, r) -> str:
    if not r.solved or not len(r.path):
        return "-"
    if r.orientations is None:  # translations at the start's orientation
        rel = np.broadcast_to(np.eye(3), (len(r.path), 3, 3))
    else:
        rel = (Rotation.from_quat(r.orientations)
               * Rotation.from_matrix(np.asarray(scene.start_rotation)).inv()).as_matrix()
    size = float(np.ptp(scene.bounds, axis=0).max())
    bad, n = pose_path_collisions(scene, r.path, rel, per_metre=1e3 / size, per_degree=100)
    return f"{bad}/{n}"


def run_planners(scenes: dict, budget: float, seeds) -> list[str]:
    rows = ["| problem | seed | cspace (default auto) | answer by | certified motions/s | "
            "colliding poses | OMPL.app's way (FCL, discrete) | colliding poses |",
            "|---|---|---|---|---|---|---|---|"]
    totals = {"ours": 0.0, "sampled": 0.0, "ours_solved": 0, "sampled_solved": 0, "n": 0}
    for name, scene in scenes.items():
        for seed in seeds:
            t = time.perf_counter()
            r = plan(scene, planner="auto", time=budget, seed=seed)
            ours = time.perf_counter() - t
            t = time.perf_counter()
            s = plan_sampled(scene, time=budget, seed=seed)
            sampled = time.perf_counter() - t
            by = r.tried[-1]["planner"] + (" SE(3)" if r.tried[-1].get("space") else "")
            rate = (f"{r.motion_checks / max(r.solve_time, 1e-9):.0f}"
                    if r.certified is not None and r.planner != "bridge" else "-")
            rows.append(
                f"| {name} | {seed} | {'solved' if r.solved else 'not solved'} in {ours:.2f} s | "
                f"{by if r.solved else ', '.join(sorted({x['planner'] for x in r.tried}))} | "
                f"{rate} | {_colliding(scene, r)} | "
                f"{'solved' if s.solved else 'not solved'} in {sampled:.2f} s | "
                f"{_colliding(scene, s)} |")
            print(rows[-1], flush=True)
            totals["ours"] += ours
            totals["sampled"] += sampled
            totals["ours_solved"] += int(r.solved)
            totals["sampled_solved"] += int(s.solved)
            totals["n"] += 1
    rows.append("")
    rows.append(f"Solved: cspace {totals['ours_solved']} of {totals['n']} runs in "
                f"{totals['ours']:.1f} s in all; OMPL.app's way {totals['sampled_solved']} of "
                f"{totals['n']} in {totals['sampled']:.1f} s (time ratio cspace / OMPL.app's way: "
                f"{totals['ours'] / max(totals['sampled'], 1e-9):.2f}).")
    return rows


def run_clearance(scenes: dict, n: int = 300) -> list[str]:
    import fcl

    from cspace.planning.se3.clearance import PoseClearance

    rows = ["| problem | triangles (world / robot) | cspace distance | cspace capped (1e-3 size) | "
            "cspace lower bound within x4 | FCL distance | FCL collide | max error vs FCL (free poses) |",
            "|---|---|---|---|---|---|---|---|"]
    rng = np.random.default_rng(1)

    def bvh(V, F):
        m = fcl.BVHModel()
        m.beginModel(len(V), len(F))
        m.addSubModel(np.ascontiguousarray(V, float), np.ascontiguousarray(F, np.int64))
        m.endModel()
        return m

    for name, scene in scenes.items():
        poses = PoseClearance(scene)
        k = poses.clearance._k
        OT, RV, RF = poses.clearance._arrays
        obstacle = fcl.CollisionObject(bvh(OT.reshape(-1, 3), np.arange(len(OT) * 3).reshape(-1, 3)))
        robot = bvh(RV, RF)
        Rs = np.ascontiguousarray(Rotation.random(n, random_state=2).as_matrix())
        size = float(np.ptp(scene.bounds, axis=0).max())
        qs = np.ascontiguousarray(scene.start + rng.normal(size=(n, 3)) * 0.05
                                  * np.ptp(scene.bounds, axis=0))
        t = time.perf_counter()
        d = k.distances(Rs, qs)
        t_full = (time.perf_counter() - t) / n
        t = time.perf_counter()
        k.distances(Rs, qs, 1e-3 * size)
        t_cap = (time.perf_counter() - t) / n
        t = time.perf_counter()
        for R, q in zip(Rs, qs):
            k.distance(R, q, np.inf, 4.0)
        t_grow = (time.perf_counter() - t) / n
        t = time.perf_counter()
        df = np.array([fcl.distance(fcl.CollisionObject(robot, fcl.Transform(R, q)), obstacle,
                                    fcl.DistanceRequest(), fcl.DistanceResult())
                       for R, q in zip(Rs, qs)])
        t_fd = (time.perf_counter() - t) / n
        t = time.perf_counter()
        hit = np.array([fcl.collide(fcl.CollisionObject(robot, fcl.Transform(R, q)), obstacle,
                                    fcl.CollisionRequest(), fcl.CollisionResult()) > 0
                        for R, q in zip(Rs, qs)])
        t_fc = (time.perf_counter() - t) / n
        err = float(np.abs(d[~hit] - df[~hit]).max()) if (~hit).any() else 0.0
        rows.append(f"| {name} | {len(OT)} / {len(RF)} | {t_full * 1e6:.0f} us | "
                    f"{t_cap * 1e6:.0f} us | {t_grow * 1e6:.0f} us | {t_fd * 1e6:.0f} us | "
                    f"{t_fc * 1e6:.0f} us | {err:.2g} (bound {poses.error_bound:.2g}) |")
        print(rows[-1], flush=True)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--time", type=float, default=30.0)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--only", default=None, help="problems whose name contains this")
    args = ap.parse_args(argv)
    load0 = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        scenes = problems(Path(tmp))
        if args.only:
            scenes = {k: v for k, v in scenes.items() if args.only in k}
        clearance = run_clearance(scenes)
        planners = run_planners(scenes, args.time, args.seeds)
    head = [BEGIN, "",
            f"## Turning while moving: cspace's default planner vs OMPL.app's way "
            f"({args.time:g} s budget, seeds {args.seeds})", "",
            f"`python benchmarks/bench_se3.py --time {args.time:g} --seeds "
            f"{' '.join(map(str, args.seeds))}` on {platform.processor() or platform.machine()}, "
            f"{os.cpu_count()} cores, {time.strftime('%Y-%m-%d')}. cspace: `plan(planner='auto')` "
            "as `cspace plan` runs it (the answer by: the attempt that solved, `bridge` a passage "
            "at one orientation joined by turns, `RRTConnect SE(3)` sampling with certified "
            "motions); OMPL.app's way: `plan_sampled` (RRTConnect in SE(3), FCL at states, "
            "discrete motions at resolution 0.01). Colliding poses: cspace's FCL oracle along "
            "every motion of the returned path (poses colliding / poses checked). Load average "
            "(1 min) at the start {:.2f}, at the end {:.2f}: other jobs share the cores.".format(
                load0[0], os.getloadavg()[0]), ""]
    body = planners + ["", "### Clearance queries at 300 random poses near each start", "",
                       "Per query. cspace: `MeshClearance` (distance; capped at 1e-3 of the "
                       "scene size, as the validity check does; a lower bound within a factor 4, "
                       "as the motion bisection asks); FCL on the same raw triangles.", ""] + clearance
    section = "\n".join(head + body + ["", END])
    report = ROOT / "benchmarks" / "reports" / "planning.md"
    text = report.read_text()
    if BEGIN in text:
        text = text[: text.index(BEGIN)] + section + text[text.index(END) + len(END):]
    else:
        text = text.rstrip() + "\n\n" + section + "\n"
    report.write_text(text)
    print(f"wrote {report}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
