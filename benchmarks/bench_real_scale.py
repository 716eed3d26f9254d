"""Real scale (issue #29): non-convex robots in OMPL.app-class worlds, against FCL in the same run.

Problems: an apartment-class world written as OMPL.app ships one (``tests/real_problems.py:
apartment``: Collada, Z_UP, one node per body, 38.7k triangles in 167 nodes round (250, 150,
-300), double-sided walls, floor and ceiling, closed and open furniture; the robot a closed
non-convex 1,668-triangle 'piano' with sliver triangles), the Parasol alpha puzzle and the
3-part flange (``../shared/data``, when present).

Per problem:

- **cold build**: a fresh process, empty disk cache: ``CSpace.from_scene`` wall seconds and
  the process's peak RSS; **cached**: the same again in a fresh process, cache filled;
- **contains**: one state at a time (as a planner asks), on states drawn half uniform in the
  bounds and half near contact (an obstacle triangle's centroid minus a robot vertex, jittered
  by 1% of the scene); FCL = ``fcl.collide`` of the robot's raw BVH at the state against one
  BVH of the world's raw triangles (OMPL.app's check), the same states, the same process;
- **segment_free**: short motions (1% of the scene) from near-contact states, one at a time;
  FCL = discrete checks along the motion every 10^-3 of the scene (stopping at the first
  collision), as OMPL's discrete motion validator does;
- agreement with the scene oracle (FCL on the raw meshes plus its own solid rule): false free
  must be 0; false collisions are counted;
- **cover** (speed against error of the robot's cover): the exact cover (robot triangles) and
  the robot's convex hull (``robot_hull=True``, its excess measured), build, ``contains`` and
  false free / false collisions on the same states;
- **planning** (apartment, alpha): ``plan(scene, slices=Orientations.uniform(64))`` (turns
  certified; where start and goal share an orientation it tries translations at it first, a
  tenth of the budget; and translations only as a row of its own) against ``plan_sampled(space='SE3')`` (OMPL.app's way: FCL, discrete motions),
  RRTConnect, same time budget and seeds; every returned path re-checked by
  ``pose_path_collisions`` (FCL on the raw meshes along the continuous motion, a pose every
  10^-4 of the scene's diagonal and every 0.1 degree).

Writes the section between the markers in benchmarks/reports/planning.md.
``python benchmarks/bench_real_scale.py [--quick]`` (quick: fewer states, no planning).
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
sys.path.insert(0, str(ROOT / "tests"))

BEGIN = "<!-- bench_real_scale: begin -->"
END = "<!-- bench_real_scale: end -->"
QUICK = "--quick" in sys.argv
N_STATES = 300 if QUICK else 2000
N_SEGMENTS = 100 if QUICK else 500
PLAN_TIME = 60.0  # the issue's `plan --orientations 64 --time 60`
SEEDS = (1, 2)

_CHILD = """
import json, resource, sys, time, warnings
t0 = time.perf_counter()
import cspace
warnings.simplefilter("ignore")
scene = cspace.load_scene(sys.argv[1])
t1 = time.perf_counter()
cs = cspace.CSpace.from_scene(scene, cache=sys.argv[2])
t2 = time.perf_counter()
# VmHWM, not ru_maxrss: Linux carries ru_maxrss over exec from the forking parent
hwm = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")]
rss = int(hwm[0].split()[1]) * 1024 if hwm else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"load": t1 - t0, "build": t2 - t1, "obstacles": len(cs.obstacles),
                  "rss": rss}))
"""


def problems(tmp: Path) -> dict[str, Path]:
    import real_problems as rp

    out = {"apartment (38.7k triangles, 167 nodes; piano robot 1,668)":
           rp.apartment(tmp / "apartment").cfg}
    ppl = SHARED / "parasol_open_ppl_env"
    if ppl.is_dir():
        out["alpha puzzle (972 x 972 triangles)"] = ppl / "alpha1.6" / "alpha.env"
        out["flange (3-part robot)"] = ppl / "flange_1.0" / "flange.env"
    return out


def fresh_build(path: Path, cache: Path) -> dict:
    r = subprocess.run([sys.executable, "-c", _CHILD, str(path), str(cache)],
                       capture_output=True, text=True, timeout=1800)
    if r.returncode:
        return {"error": (r.stderr.strip().splitlines() or ["?"])[-1]}
    return json.loads(r.stdout.strip().splitlines()[-1])


class RawFcl:
    """OMPL.app's check: the robot's raw BVH at a translation against the world's raw BVH."""

    def __init__(self, scene):
        import fcl

        self.fcl = fcl
        V = np.vstack([b.vertices for b in scene.obstacles])
        off = np.cumsum([0] + [len(b.vertices) for b in scene.obstacles])[:-1]
        F = np.vstack([b.faces + o for b, o in zip(scene.obstacles, off)])
        world = fcl.BVHModel()
        world.beginModel(len(F), len(V))
        world.addSubModel(np.asarray(V, np.float64), np.asarray(F, np.int64))
        world.endModel()
        self.world = fcl.CollisionObject(world, fcl.Transform())
        c = np.asarray(scene.reference_point, np.float64)
        robot = fcl.BVHModel()
        robot.beginModel(len(scene.robot.faces), len(scene.robot.vertices))
        robot.addSubModel(np.asarray(scene.robot.vertices, np.float64) - c,
                          np.asarray(scene.robot.faces, np.int64))
        robot.endModel()
        self.robot = fcl.CollisionObject(robot, fcl.Transform())
        self.request = fcl.CollisionRequest()

    def collides(self, q) -> bool:
        self.robot.setTranslation(np.asarray(q, np.float64))
        return self.fcl.collide(self.robot, self.world, self.request,
                                self.fcl.CollisionResult()) > 0


def states(scene, rng, n):
    lo, hi = np.asarray(scene.bounds, np.float64)
    extent = float(np.linalg.norm(hi - lo))
    tris = np.vstack([b.vertices[b.faces].mean(axis=1) for b in scene.obstacles])
    c = np.asarray(scene.reference_point, np.float64)
    r = scene.robot.vertices[rng.integers(0, len(scene.robot.vertices), n // 2)] - c
    near = tris[rng.integers(0, len(tris), n // 2)] - r + rng.normal(size=r.shape) * 0.01 * extent
    uniform = lo + (hi - lo) * rng.random((n - n // 2, 3))
    q = np.vstack([uniform, near])
    return q[((lo <= q) & (q <= hi)).all(axis=1)], extent


def per_call(f, items) -> tuple[float, list]:
    out = []
    t = time.perf_counter()
    for x in items:
        out.append(f(x))
    return (time.perf_counter() - t) / len(items), out


def queries(scene, cs, rng) -> dict:
    from cspace.check.oracle import SceneOracle

    fcl_ = RawFcl(scene)
    Q, extent = states(scene, rng, N_STATES)
    cs.contains(Q[0])  # first-call imports
    t_ours, ours = per_call(cs.contains, Q)
    t_fcl, theirs = per_call(fcl_.collides, Q)
    truth = SceneOracle(scene).collides(Q)
    ours, truth = np.array(ours), np.asarray(truth)
    # short motions from the near-contact half, 1% of the scene long
    A = Q[len(Q) // 2:][:N_SEGMENTS]
    d = rng.normal(size=A.shape)
    B = A + d / np.linalg.norm(d, axis=1, keepdims=True) * 0.01 * extent
    lo, hi = np.asarray(scene.bounds)
    B = np.clip(B, lo, hi)
    t_seg, _ = per_call(lambda ab: cs.segment_free(*ab), list(zip(A, B)))
    step = 1e-3 * extent

    def discrete(ab):
        a, b = ab
        n = int(np.ceil(np.linalg.norm(b - a) / step)) + 1
        return not any(fcl_.collides(a + (b - a) * t) for t in np.linspace(0.0, 1.0, n))

    t_seg_fcl, _ = per_call(discrete, list(zip(A, B)))
    return {"n": len(Q), "contains_us": t_ours * 1e6, "fcl_us": t_fcl * 1e6,
            "false_free": int((~ours & truth).sum()), "false_coll": int((ours & ~truth).sum()),
            "raw_fcl_disagree": int((np.array(theirs) != truth).sum()),
            "segments": len(A), "segment_us": t_seg * 1e6, "fcl_segment_us": t_seg_fcl * 1e6}


def hull_excess(scene, rng, n: int = 20000) -> float:
    """How far the robot's convex hull reaches beyond the robot: the largest distance from
    points on the hull's surface (area-weighted samples) to the robot (FCL's distance to the
    raw mesh; no surface point of the hull lies inside the robot's interior, which the hull's
    interior holds). A lower bound from samples."""
    import fcl
    from scipy.spatial import ConvexHull

    V = np.asarray(scene.robot.vertices, np.float64)
    h = ConvexHull(V)
    T = V[h.simplices]
    area = np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    pick = rng.choice(len(T), n, p=area / area.sum())
    w = rng.dirichlet(np.ones(3), n)
    P = np.einsum("ki,kij->kj", w, T[pick])
    bvh = fcl.BVHModel()
    bvh.beginModel(len(scene.robot.faces), len(V))
    bvh.addSubModel(V, np.asarray(scene.robot.faces, np.int64))
    bvh.endModel()
    robot = fcl.CollisionObject(bvh, fcl.Transform())
    point = fcl.CollisionObject(fcl.Sphere(0.0), fcl.Transform())
    best = 0.0
    for p in P:
        point.setTranslation(p)
        best = max(best, fcl.distance(robot, point, fcl.DistanceRequest(), fcl.DistanceResult()))
    return float(best)


def covers(scene, rng, fcl_us: float) -> list[dict]:
    """The two ends of the robot-cover knob on the same states: the exact cover (one triangle
    per piece: triangle pairs, what a build does by default) and the robot's convex hull (one
    piece; conservative, its excess is false collisions). Builds in this process, no cache."""
    import gc

    import cspace
    from cspace.check.oracle import SceneOracle

    Q, extent = states(scene, rng, N_STATES)
    truth = np.asarray(SceneOracle(scene).collides(Q))
    rows = []
    for cover, hull in (("exact: robot triangles (triangle pairs)", False),
                        ("conservative: robot's convex hull", True)):
        gc.collect()
        t0 = time.perf_counter()
        cs = cspace.CSpace.from_scene(scene, robot_hull=hull)
        build = time.perf_counter() - t0
        cs.contains(Q[0])
        t, ours = per_call(cs.contains, Q)
        ours = np.array(ours)
        excess = hull_excess(scene, rng) if hull else 0.0
        rows.append({"cover": cover, "pieces": 1 if hull else len(scene.robot.faces),
                     "excess": excess, "excess_rel": excess / extent, "build_s": build,
                     "contains_us": t * 1e6, "ratio": fcl_us / (t * 1e6), "n": len(Q),
                     "false_free": int((~ours & truth).sum()),
                     "false_coll": int((ours & ~truth).sum())})
        print(rows[-1], flush=True)
        del cs
    return rows


def planning(scene) -> list[dict]:
    from scipy.spatial.transform import Rotation

    from cspace.check.cross_check import pose_path_collisions
    from cspace.planning.orientations import Orientations
    from cspace.planning.plan import plan
    from cspace.planning.sampled import plan_sampled

    rel = np.asarray(scene.goal_rotation) @ np.asarray(scene.start_rotation).T
    slices = Orientations.uniform(64, goal_rotation=rel)
    start_rot = np.asarray(scene.start_rotation)
    extent = float(np.linalg.norm(np.ptp(np.asarray(scene.bounds, np.float64), axis=0)))
    rows = [turn_build(scene, slices)]
    same = np.allclose(scene.goal_rotation, scene.start_rotation)
    methods = (["ours, translations only"] if same else []) + [
        "ours, 64 orientations", "OMPL.app-style SE3 (FCL)"]
    for method in methods:
        solved, times, clipping, first = 0, [], 0, 0
        for seed in SEEDS:
            if method == "ours, translations only":
                r = plan(scene, time=PLAN_TIME, seed=seed)
            elif method.startswith("ours"):
                r = plan(scene, slices=slices, time=PLAN_TIME, seed=seed)
            else:
                r = plan_sampled(scene, space="SE3", time=PLAN_TIME, seed=seed)
            if not r.solved:
                continue
            solved += 1
            times.append(r.time)
            first += bool(r.built and r.built.get("start_orientation_only"))
            if r.orientations is None:  # translations only: the start orientation throughout
                R = np.repeat(np.eye(3)[None], len(r.path), axis=0)
            else:
                R = Rotation.from_quat(r.orientations).as_matrix() @ start_rot.T
            bad, _ = pose_path_collisions(scene, r.path, R, per_metre=1e4 / extent,
                                          per_degree=10.0)
            clipping += bad > 0
        rows.append({"method": method, "solved": solved, "runs": len(SEEDS),
                     "mean_s": float(np.mean(times)) if times else None, "clipping": clipping,
                     "rss": _peak_rss(),
                     "first": first if method == "ours, 64 orientations" else None})
        print(rows[-1], flush=True)
    return rows


def _peak_rss() -> int:
    """This process's peak resident memory so far (bytes; VmHWM)."""
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
    return 0


def turn_build(scene, slices) -> dict:
    """Seconds to make the start orientation's slice, then one turn in place from it to a
    neighbour (no disk cache; both lazy: bodies are built at the first query near them)."""
    from cspace.planning.turning import TurningCSpace

    tc = TurningCSpace(scene, slices, cache=None)
    t0 = time.perf_counter()
    tc.slice(0)
    t1 = time.perf_counter()
    k = next(k for k in range(1, len(slices)) if slices.neighbours(0, k))
    tc.turn(0, k)
    t2 = time.perf_counter()
    row = {"turn": True, "slice_s": t1 - t0, "turn_s": t2 - t1,
           "step_deg": float(np.degrees(slices.step(0, k)))}
    print(row, flush=True)
    return row


def main():
    import cspace

    warnings.simplefilter("ignore")
    load0 = os.getloadavg()
    rng = np.random.default_rng(0)
    lines = ["## Real scale: non-convex robots in OMPL.app-class worlds (issue #29)", "",
             f"`python benchmarks/bench_real_scale.py`; {platform.processor() or platform.machine()}, "
             f"{os.cpu_count()} cores, load average at start {', '.join(f'{x:.2f}' for x in load0)}. "
             "Triangle pairs are found per query by two k-DOP trees (26-DOPs; no pair is enumerated); "
             "every answer exact. Builds in a fresh process with an empty disk cache (cold) and "
             "again with it filled (cached); queries one state at a time in one process, FCL "
             "(`fcl.collide`, robot BVH against one world BVH, raw meshes) on the same states "
             "in the same run; 'ratio' = FCL time / ours (above 1: ours faster). False free / "
             "false collisions against the scene oracle (FCL on the raw meshes with its own "
             "solid rule).", "",
             "| problem | cold build s | peak RSS | cached s | C-obstacles | contains µs | FCL collide µs | ratio | short segment µs | FCL discrete (10^-3) µs | ratio | false free | false collisions |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    plans, cover_rows = [], []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name, path in problems(tmp).items():
            cache = tmp / f"cache{len(plans)}{hash(name) % 1000}"
            cold = fresh_build(path, cache)
            if "error" in cold:
                lines.append(f"| {name} | failed: {cold['error']} |" + " |" * 12)
                print(lines[-1], flush=True)
                continue
            warm = fresh_build(path, cache)
            scene = cspace.load_scene(path)
            cs = cspace.CSpace.from_scene(scene, cache=cache)
            q = queries(scene, cs, rng)
            lines.append(
                f"| {name} | {cold['build']:.2f} | {cold['rss'] / 2**20:.0f} MB | "
                f"{warm['build']:.2f} | {cold['obstacles']} | {q['contains_us']:.0f} | "
                f"{q['fcl_us']:.0f} | {q['fcl_us'] / q['contains_us']:.2f} | "
                f"{q['segment_us']:.0f} | {q['fcl_segment_us']:.0f} | "
                f"{q['fcl_segment_us'] / q['segment_us']:.2f} | {q['false_free']}/{q['n']} | "
                f"{q['false_coll']}/{q['n']} |")
            print(lines[-1], flush=True)
            del cs
            cover_rows.append((name, covers(scene, rng, q["fcl_us"])))
            if not QUICK and not name.startswith("flange"):
                plans.append((name, planning(scene)))
    if cover_rows:
        lines += ["", "Speed against error of the robot's cover, its two ends, on the same "
                  "states (half uniform, half near contact): the exact cover (each robot "
                  "triangle a piece, with the containment terms: the default) and the robot's "
                  "convex hull (`robot_hull=True`: one piece, conservative). Excess: how far the "
                  "hull reaches beyond the robot (largest distance from 20,000 points on the "
                  "hull's surface to the robot's solid; a lower bound), absolute and relative "
                  "to the scene's diagonal S; its errors can only be false collisions. Builds in "
                  "this process, no cache; 'ratio' = FCL collide time (table above) / ours.", "",
                  "| problem | cover | pieces | excess | excess / S | build s | contains µs | "
                  "ratio | false free | false collisions |", "|---|---|---|---|---|---|---|---|---|---|"]
        for name, rows in cover_rows:
            for r in rows:
                lines.append(
                    f"| {name} | {r['cover']} | {r['pieces']:,} | {r['excess']:.3g} | "
                    f"{r['excess_rel']:.2g} | {r['build_s']:.2f} | {r['contains_us']:.0f} | "
                    f"{r['ratio']:.2f} | {r['false_free']}/{r['n']} | "
                    f"{r['false_coll']}/{r['n']} |")
    if plans:
        lines += ["", f"Planning ({len(SEEDS)} seeds, RRTConnect, {PLAN_TIME:.0f} s each; "
                  "'clipping' = returned paths with a colliding pose when re-checked by FCL "
                  "along the continuous motion, a pose every 10^-4 of the scene's diagonal and "
                  "every 0.1 degree):", "",
                  "| problem | method | solved | mean s | clipping paths | of them translations at "
                  "the start orientation alone | this process's peak RSS after it |",
                  "|---|---|---|---|---|---|---|"]
        turns = []
        for name, rows in plans:
            for r in rows:
                if r.get("turn"):
                    turns.append(f"- {name}: one orientation slice {r['slice_s']:.2f} s, one "
                                 f"turn in place to a neighbour ({r['step_deg']:.0f}°) "
                                 f"{r['turn_s']:.2f} s")
                    continue
                mean = f"{r['mean_s']:.2f}" if r["mean_s"] is not None else "–"
                alone = "" if r.get("first") is None else f"{r['first']}/{r['solved']}"
                lines.append(f"| {name} | {r['method']} | {r['solved']}/{r['runs']} | {mean} | "
                             f"{r['clipping']}/{r['solved']} | {alone} | "
                             f"{r['rss'] / 2**20:.0f} MB |")
    if plans:
        lines += ["", "What a turning planner pays the first time it reaches a slice or a turn "
                  "(in this process, no disk cache; the first slice also models the obstacles, "
                  "once for all orientations; both are lazy, a body's C-obstacles built at the "
                  "first query near it; a turn's are the robot parts' swept hulls against "
                  "every body as triangle pairs, convex bodies by CVMS):", ""] + turns
    lines.append("")
    report = ROOT / "benchmarks" / "reports" / "planning.md"
    text = report.read_text() if report.exists() else ""
    section = BEGIN + "\n" + "\n".join(lines) + "\n" + END
    if BEGIN in text:
        a, b = text.index(BEGIN), text.index(END) + len(END)
        text = text[:a] + section + text[b:]
    else:
        text = text.rstrip() + "\n\n" + section + "\n"
    report.write_text(text)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
