"""Benchmark: what a fresh process pays before its first answer (issue #18).

Each measurement runs in fresh subprocesses (``python -c ...``), nothing cached on disk that a
first run after installation would not have (the C-obstacle cache is pointed at an empty
folder; the compiled kernels are part of the installation, as their build is):

- ``import cspace`` (median of 5 processes);
- the first ``contains`` / ``segment_free`` / ``signed_distance`` on a mesh C-obstacle (a
  torus ⊕ icosphere, 1000 queries each) in a fresh process, against the same calls repeated
  in that process (*warm*);
- the first ``minkowski_sum`` of torus(20480 triangles) ⊕ ico320 in a fresh process against a
  second one in the same process (the issue's bar: cold within 1.5x of warm);
- ``cspace build`` of a scene of 10^3 (and 10^4) random boxes centred at (250, 150, -300), a
  box robot (issue #30's bar for 10^3: under 1 s of build time, under 1.5 s in all, a fresh
  process with an empty cache), then the same command again with the cache filled; beside
  it, in the same run, the peer's set-up in a fresh process: FCL's collision objects for the
  same boxes in a dynamic AABB tree manager (what FCL pays before its first query).

Usage: ``python benchmarks/bench_cold_start.py [--out PATH]`` writes
``benchmarks/reports/cold_start.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REPORT = ROOT / "benchmarks" / "reports" / "cold_start.md"

IMPORT = "import time; t = time.perf_counter(); import cspace; print(time.perf_counter() - t)"

QUERIES = f"""
import json, sys, time
sys.path.insert(0, {str(ROOT / 'tests')!r})
import numpy as np, zoo
from cspace import CSpaceObstacle
V, F = zoo.torus()
co = CSpaceObstacle.build((V, F), zoo.icosphere_points(1, radius=0.3))
q = np.random.default_rng(0).uniform(-2, 2, (1000, 3))
out = {{}}
for name, call in (("contains", lambda: co.contains(q)),
                   ("segment_free", lambda: co.segment_free(q[:-1], q[1:])),
                   ("signed_distance", lambda: co.signed_distance(q))):
    t = time.perf_counter(); call(); cold = time.perf_counter() - t
    t = time.perf_counter(); call(); warm = time.perf_counter() - t
    out[name] = (cold, warm)
print(json.dumps(out))
"""

SUM = f"""
import json, sys, time
sys.path.insert(0, {str(ROOT / 'tests')!r})
import zoo
from cspace import minkowski_sum
V, F = zoo.torus(sections=160, ring=64)
B = zoo.icosphere_points(2, radius=0.3)
t = time.perf_counter(); minkowski_sum((V, F), B); cold = time.perf_counter() - t
t = time.perf_counter(); minkowski_sum((V, F), B); warm = time.perf_counter() - t
print(json.dumps({{"triangles": len(F), "cold": cold, "warm": warm}}))
"""


FCL_SETUP = """
import os, sys, time, tomllib
t = time.perf_counter()
import fcl, numpy as np
scene = tomllib.load(open(sys.argv[1], "rb"))
meshes = {}
def geometry(o):  # a box, or a mesh file scaled (one BVH model per file and scale, shared)
    if "box" in o:
        return fcl.Box(*o["box"])
    key = (o["mesh"], o.get("scale", 1.0))
    if key not in meshes:
        rows = open(os.path.join(os.path.dirname(sys.argv[1]), o["mesh"])).read().split("\\n")
        V = np.array([r.split()[1:] for r in rows if r.startswith("v ")], float) * key[1]
        F = np.array([r.split()[1:] for r in rows if r.startswith("f ")], int) - 1
        m = fcl.BVHModel()
        m.beginModel(len(V), len(F))
        m.addSubModel(V, F)
        m.endModel()
        meshes[key] = m
    return meshes[key]
objs = [fcl.CollisionObject(geometry(o), fcl.Transform(np.array(o["position"], float)))
        for o in scene["obstacles"]]
manager = fcl.DynamicAABBTreeCollisionManager()
manager.registerObjects(objs)
manager.setup()
print(time.perf_counter() - t)
"""


PHASES = """
import json, sys, time
t = time.perf_counter()
from cspace.scene.files import load_scene
from cspace.scene.model import model_scene
t0 = time.perf_counter()
scene = load_scene(sys.argv[1])
t1 = time.perf_counter()
model = model_scene(scene, cache=sys.argv[2])
t2 = time.perf_counter()
cs = model.cspace()
t3 = time.perf_counter()
cs.contains(scene.start)
t4 = time.perf_counter()
print(json.dumps({"import": t0 - t, "read": t1 - t0, "model": model.seconds["model"],
                  "build": model.seconds["build"], "cspace": t3 - t2, "query": t4 - t3,
                  "restored": sum(b.cache == "hit" for b in model.bodies)}))
"""


def boxes_scene(path: Path, n: int, seed: int = 0, l_every: int = 0) -> Path:
    """A scene file of ``n`` random boxes in a cube of side ``10 (n / 1000)^(1/3)`` at
    (250, 150, -300), and a 0.3 x 0.15 x 0.1 box robot; ``l_every``: every ``l_every``-th
    body instead a non-convex L-shape (``L.obj`` beside the file, scaled 0.15: the mix of
    ``bench_scale.synthetic_world``)."""
    import numpy as np

    if l_every:
        sys.path.insert(0, str(ROOT / "tests"))
        import zoo

        V, F = zoo.l_shape()
        V = V - V.mean(axis=0)
        (path.parent / "L.obj").write_text(
            "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
            + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F.tolist()))

    rng = np.random.default_rng(seed)
    side = 10.0 * (n / 1000) ** (1 / 3)
    at = np.array([250.0, 150.0, -300.0])
    lines = [f'name = "boxes{n}"', "", "[robot]", "box = [0.3, 0.15, 0.1]", "", "[planning]",
             f"bounds = [{at.tolist()}, {(at + side).tolist()}]",
             f"start = {(at + 0.01).tolist()}", f"goal = {(at + side - 0.01).tolist()}", ""]
    for i in range(n):
        size, centre = rng.uniform(0.05, 0.4, 3), at + rng.uniform(0.0, side, 3)
        shape = (['mesh = "L.obj"', "scale = 0.15"] if l_every and i % l_every == 7 else
                 ["box = [" + ", ".join(f"{x:.4f}" for x in size) + "]"])
        lines += ["[[obstacles]]", f'name = "b{i}"', *shape,
                  "position = [" + ", ".join(f"{x:.4f}" for x in centre) + "]", ""]
    path.write_text("\n".join(lines))
    return path


def cli_build(scene: Path, cache: Path) -> tuple[float, float]:
    """Wall time of ``cspace build SCENE`` in a fresh process, and the build time it prints."""
    import re
    import time

    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "cspace", "build", str(scene), "--cache-dir",
                          str(cache)], env=env, capture_output=True, text=True, timeout=1800)
    wall = time.perf_counter() - t
    if out.returncode:
        raise RuntimeError(out.stderr[-800:])
    built = re.search(r"built (\d+) C-obstacles in ([0-9.]+) s", out.stdout + out.stderr)
    return wall, float(built.group(2))


def build_rows(sizes=((1000, 0), (10000, 0), (10000, 50)), repeats: int = 5) -> list[dict]:
    """Per scene (size, every how many bodies an L-shape): ``cspace build`` with an empty
    cache and with it filled (median of ``repeats`` fresh processes for 10^3, one for larger),
    and FCL's set-up."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n, l_every in sizes:
            folder = Path(tmp) / f"scene{n}-{l_every}"
            folder.mkdir()
            scene = boxes_scene(folder / f"boxes{n}.toml", n, l_every=l_every)
            k = repeats if n <= 1000 else 1
            cold, warm, fcl_ = [], [], []
            for i in range(k):
                cache = folder / f"cache{i}"
                cold.append(cli_build(scene, cache))
                warm.append(cli_build(scene, cache))
                fcl_.append(float(subprocess.run(
                    [sys.executable, "-c", FCL_SETUP, str(scene)], capture_output=True,
                    text=True, timeout=900, check=True).stdout.split()[-1]))
            # where a cached run's time goes, in one more fresh process
            phases = json.loads(subprocess.run(
                [sys.executable, "-c", PHASES, str(scene), str(folder / "cache0")],
                capture_output=True, text=True, timeout=900, check=True).stdout.split("\n")[-2])
            med = lambda xs: statistics.median(xs)  # noqa: E731
            label = f"{n}" + (f", every {l_every}th an L-shape" if l_every else "")
            rows.append({"n": n, "label": label, "runs": k, "cold": med([w for w, _ in cold]),
                         "cold_build": med([b for _, b in cold]),
                         "warm": med([w for w, _ in warm]), "warm_build": med([b for _, b in warm]),
                         "fcl": med(fcl_), "phases": phases})
    return rows


def run(code: str) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, CSPACE_CACHE=tmp, PYTHONDONTWRITEBYTECODE="1")
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                             text=True, timeout=900, cwd=tmp)
    if out.returncode:
        raise RuntimeError(out.stderr[-800:])
    return out.stdout.strip().splitlines()[-1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=REPORT)
    args = ap.parse_args()
    load0 = os.getloadavg()
    imports = sorted(float(run(IMPORT)) for _ in range(5))
    queries = json.loads(run(QUERIES))
    sums = json.loads(run(SUM))
    builds = build_rows()
    load1 = os.getloadavg()
    lines = [
        "# Cold start: the first answer in a fresh process", "",
        f"Generated by `python benchmarks/bench_cold_start.py` on {os.cpu_count()} CPUs, Python "
        f"{platform.python_version()}; load average {load0[0]:.2f} at the start, "
        f"{load1[0]:.2f} at the end. Every row is a fresh subprocess with an empty C-obstacle "
        "cache; the compiled kernels (Cython) were built at install time, nothing is compiled "
        "at run time.", "",
        f"`import cspace`: median {statistics.median(imports):.3f} s over 5 processes "
        f"(min {imports[0]:.3f}, max {imports[-1]:.3f}).", "",
        "| call | first in the process (s) | repeated (s) | first / repeated |",
        "|---|---|---|---|",
    ]
    for name, (cold, warm) in queries.items():
        lines.append(f"| {name} (1000 queries, torus ⊕ ico80 C-obstacle) | {cold:.4f} | "
                     f"{warm:.4f} | {cold / warm:.2f} |")
    lines.append(f"| minkowski_sum torus({sums['triangles']}) ⊕ ico320 | {sums['cold']:.2f} | "
                 f"{sums['warm']:.2f} | {sums['cold'] / sums['warm']:.2f} |")
    lines += [
        "", "## `cspace build` of many boxes, a fresh process", "",
        "A scene file of N random boxes (0.05-0.4 a side) centred at (250, 150, -300) and a box "
        "robot (one scene also with every 50th body a non-convex L-shape, a mesh file: the mix "
        "of `benchmarks/reports/scale.md`, whose 200 solids the snapshot restores validated); "
        "`cspace build SCENE --cache-dir EMPTY` in a fresh process (*cold*: wall time of "
        "the whole command, import, reading, modelling, building, writing the cache), then the "
        "same command again (*cached*: the model and every C-obstacle restored from the "
        "scene's snapshot in the pack). *Build* is the time the command prints for building the C-obstacles. *FCL set-up*: a fresh process "
        "that reads the same file and makes FCL's boxes in a dynamic AABB tree manager, in the "
        "same run (what FCL pays before its first query; it builds no C-obstacle). Median of "
        "the processes run.", "",
        "| N bodies | processes | cold, all (s) | cold, build (s) | cached, all (s) | "
        "cached, build (s) | cold / cached | FCL set-up (s) | cold / FCL set-up |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in builds:
        lines.append(f"| {r['label']} | {r['runs']} | {r['cold']:.2f} | {r['cold_build']:.2f} | "
                     f"{r['warm']:.2f} | {r['warm_build']:.2f} | {r['cold'] / r['warm']:.2f} | "
                     f"{r['fcl']:.2f} | {r['cold'] / r['fcl']:.1f} |")
    lines += [
        "", "Where a cached run's time goes (one more fresh process, `load_scene`, "
        "`model_scene(scene, cache=FOLDER)`, `.cspace()` and one `contains` in Python): "
        "importing the modules that read and model a scene, reading the scene file (TOML "
        "parsing and the bodies' arrays), modelling (here: the scene's snapshot found by a key "
        "over its whole input and every body restored from it, `cspace.scene.snapshot`), "
        "making the C-obstacles (from the snapshot), making the queryable `CSpace` (its box "
        "tree over every C-obstacle), and the first query. *Loaded* is modelling + "
        "C-obstacles + `CSpace`: everything after the file is read.", "",
        "| N bodies | import (s) | reading the file (s) | modelling (s) | C-obstacles (s) | "
        "CSpace (s) | first query (s) | **loaded** (s) | bodies from the cache |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in builds:
        ph = r["phases"]
        loaded = ph["model"] + ph["build"] + ph["cspace"]
        lines.append(f"| {r['label']} | {ph['import']:.2f} | {ph['read']:.2f} | "
                     f"{ph['model']:.2f} | "
                     f"{ph['build']:.2f} | {ph['cspace']:.2f} | {ph['query']:.4f} | "
                     f"**{loaded:.2f}** | {ph['restored']} of {r['n']} |")
    text = "\n".join(lines) + "\n"
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
