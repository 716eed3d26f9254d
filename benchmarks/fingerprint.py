"""A deterministic fingerprint of cspace's outputs, through the top-level public API only.

It exists to prove that a restructure (modules moving into subpackages, helpers renamed)
changes no output: run it before and after, then ``--compare`` the two files. It therefore
imports ``cspace`` and names from ``cspace`` itself, numpy and trimesh, and nothing from a
``cspace.<submodule>`` or from ``tests/`` (those paths are what a restructure moves).

What it records (every input fixed, every random draw seeded):

- ``api``: ``cspace.__all__`` and the parameters (names, kinds, defaults) of its functions
  and of the public members of its classes (inherited ones included).
- ``sum/*``: Minkowski sums, convex ⊕ convex (``convex_minkowski_sum`` and the CVMS path of
  ``minkowski_sum``), non-convex closed ⊕ convex (``minkowski_sum``, NCC-CVMS: an L prism by
  hand, a torus, an annulus, genus-1 and scanned meshes of ``../shared/data`` when present),
  two boxes sharing an edge (the union of two bodies' sums), an off-origin case (operands translated by
  (250, 150, -300)), scaled cases and a reflected robot. Per case: sha256 of the vertices
  (float64) and faces (int64), counts, the exact volume (a rational, as text), the float
  volume, ``error_bound``, holes, non-manifold features, facet kinds, and the superset's
  sizes and hashes (``minkowski_superset``).
- ``co/*``: C-obstacles from ``CSpaceObstacle.build`` (convex, mesh, a union of pieces; both
  ``conservative=True`` and ``False``), with query answers (and ``plane_signs`` when convex).
- ``scene/*``: every ``scenes/*.toml``, plus FCL's environment (``scenes/shared/fcl_env.toml``),
  Parasol's bug trap and a scene of closed non-convex meshes when ``../shared/data`` is there:
  ``load_scene`` -> ``model_scene(cache=None)`` -> ``.cspace()``; the model (per body: kind,
  reason, meaning change, sizes, constructions; ``explain()`` with timings blanked; counts,
  grid, error bound), each C-obstacle (kind, bounds, sizes, hashes, error bound), and the
  answers to 200 random points plus boundary points (``contains``, ``signed_distance``) and 50
  random segments (45 local steps, 5 across the box) plus start-goal (``segment_free``,
  ``first_contact``), for the whole C-space and hashed per C-obstacle. A C-obstacle of
  triangle pairs (10^5 pieces, hulls built on demand) is fingerprinted by its pairs and the
  hulls of 64 pieces drawn with a fixed seed. A query that raises records its error (and,
  for segments, each segment's answer on its own).
- ``meta``: numpy's and trimesh's versions, and whether ``../shared/data`` was there.

Floats are written with ``repr`` (shortest round-trip text: equal text is equal bits).
Nothing machine-dependent (times, paths) is recorded.

Usage::

    python benchmarks/fingerprint.py [OUT.json]        # default: stdout
    python benchmarks/fingerprint.py --compare A.json B.json   # exit 1 if any entry differs

Builds run in this process (``CSPACE_WORKERS=1``; results do not depend on it) and the disk
cache is off, so runs are independent. About a minute on one core.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import os
import re
import sys
import tempfile
import time
import warnings
from fractions import Fraction
from pathlib import Path

os.environ["CSPACE_WORKERS"] = "1"  # before cspace reads it; results do not depend on it

import numpy as np  # noqa: E402
import trimesh  # noqa: E402

import cspace  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
OFFSET = np.array([250.0, 150.0, -300.0])
N_POINTS, N_SEGMENTS, N_LONG = 200, 50, 5


# --------------------------------------------------------------------------------------
# encoding helpers


def sha(a, dtype) -> str:
    a = np.ascontiguousarray(np.asarray(a, dtype=dtype))
    h = hashlib.sha256()
    h.update(str(a.shape).encode())
    h.update(a.tobytes())
    return h.hexdigest()


def fl(x) -> str:
    return repr(float(x))


def fls(a) -> list:
    return [repr(float(x)) for x in np.asarray(a, dtype=np.float64).reshape(-1)]


def bits(a) -> str:
    """A bool array as a '0'/'1' string."""
    return "".join("1" if b else "0" for b in np.asarray(a, dtype=bool).reshape(-1))


def rational(q) -> str:
    """An exact rational as text, ``p/q``; a long one as the sha256 of its hex text and the
    bit lengths of its terms (the exact volumes of non-convex sums run to thousands of digits)."""
    q = Fraction(q)
    text = f"{hex(q.numerator)}/{hex(q.denominator)}"
    if len(text) > 160:
        return (f"sha256:{hashlib.sha256(text.encode()).hexdigest()} "
                f"bits:{q.numerator.bit_length()}/{q.denominator.bit_length()}")
    return f"{q.numerator}/{q.denominator}"


def counts_of(kind, names) -> dict:
    kind = np.asarray(kind).reshape(-1)
    return {str(n): int(np.count_nonzero(kind == k)) for k, n in enumerate(names)}


# --------------------------------------------------------------------------------------
# operands (plain arrays; nothing from tests/)


def mesh_arrays(m) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)


def prism(polygon, height: float, fan: int):
    """A closed prism over a simple polygon (counter-clockwise in xy), its caps fanned from
    vertex ``fan`` (which must see every other vertex)."""
    P = np.asarray(polygon, dtype=np.float64)
    n = len(P)
    V = np.vstack([np.c_[P, np.zeros(n)], np.c_[P, np.full(n, height)]])
    F = []
    order = [(fan + k) % n for k in range(n)]
    for a, b in zip(order[1:-1], order[2:]):
        F.append((fan + n, a + n, b + n))  # top, counter-clockwise from above
        F.append((fan, b, a))  # bottom, reversed
    for i in range(n):
        j = (i + 1) % n
        F += [(i, j, j + n), (i, j + n, i + n)]
    return V, np.array(F, dtype=np.int64)


def l_prism():
    return prism([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], 0.7, fan=3)


def box(extents=(1.0, 1.0, 1.0), at=(0.0, 0.0, 0.0)):
    V, F = mesh_arrays(trimesh.creation.box(extents=extents))
    return V + np.asarray(at, dtype=np.float64), F


def icosphere(subdivisions: int, radius: float):
    return mesh_arrays(trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius))


def cylinder(radius: float, height: float, sections: int):
    return mesh_arrays(trimesh.creation.cylinder(radius=radius, height=height, sections=sections))


def torus():
    return mesh_arrays(trimesh.creation.torus(major_radius=1.0, minor_radius=0.3,
                                              major_sections=24, minor_sections=12))


def annulus():
    return mesh_arrays(trimesh.creation.annulus(r_min=0.6, r_max=1.0, height=0.4, sections=20))


def hull_points(n: int, radius: float, seed: int) -> np.ndarray:
    p = np.random.default_rng(seed).normal(size=(n, 3))
    return radius * p / np.linalg.norm(p, axis=1, keepdims=True)


def edge_boxes():
    """Two unit cubes sharing an edge (welded): closed pieces meeting at a non-manifold edge."""
    V1, F1 = box(at=(0.5, 0.5, 0.5))
    V2, F2 = box(at=(1.5, 1.5, 0.5))
    V = np.vstack([V1, V2])
    F = np.vstack([F1, F2 + len(V1)])
    uniq, inv = np.unique(V, axis=0, return_inverse=True)
    return uniq, inv.reshape(-1)[F]


def moved(op, offset=None, scale=1.0):
    """``op`` ((V, F) or points) scaled then translated."""
    off = np.zeros(3) if offset is None else np.asarray(offset, dtype=np.float64)
    if isinstance(op, tuple):
        return op[0] * scale + off, op[1]
    return np.asarray(op, dtype=np.float64) * scale + off


def shared_mesh(rel: str):
    path = SHARED / rel
    return cspace.as_mesh(str(path)) if path.is_file() else None


# --------------------------------------------------------------------------------------
# fingerprints of results


def fp_grid(g) -> dict:
    return {"exponent": int(g.exponent), "bits": int(g.bits),
            "origin": [int(x) for x in g.origin]}


def fp_polytope(P) -> dict:
    return {"vertices": len(P.vertices), "facets": int(P.n_facets),
            "vertices_sha": sha(P.vertices, np.float64), "faces_sha": sha(P.faces, np.int64),
            "ints_sha": sha(P.ints, np.int64), "normals_sha": sha(P.normals, np.int64),
            "facet_degrees": sha(P.facet_degrees, np.int64), "volume6": str(int(P.volume6())),
            "excess": fl(P.excess), "grid": fp_grid(P.grid)}


def fp_closed_mesh(M) -> dict:
    return {"vertices": len(M.vertices), "faces": len(M.faces),
            "vertices_sha": sha(M.vertices, np.float64), "faces_sha": sha(M.faces, np.int64),
            "ints_sha": sha(M.ints, np.int64), "volume6": str(int(M.volume6())),
            "components_sha": sha(M.components, np.int64), "grid": fp_grid(M.grid)}


def fp_surface(S) -> dict:
    """What every sum has: vertices, faces, a trimesh of them, the error bound."""
    V, F = np.asarray(S.vertices), np.asarray(S.faces)
    tm = S.to_trimesh()
    return {"type": type(S).__name__, "vertices": len(V), "faces": len(F),
            "vertices_sha": sha(V, np.float64), "faces_sha": sha(F, np.int64),
            "error_bound": fl(S.error_bound),
            "trimesh_sha": sha(tm.vertices, np.float64) + ":" + sha(tm.faces, np.int64),
            "bounds": fls(np.stack([V.min(axis=0), V.max(axis=0)]))}


def fp_minkowski_sum(S) -> dict:
    """A ``convex_minkowski_sum`` result."""
    out = fp_surface(S)
    P = S.polytope
    exact = Fraction(int(P.volume6()), 6) * Fraction(2) ** (3 * S.grid.exponent)
    out.update(volume=fl(S.volume), volume_exact=rational(exact), facets=len(S.facets),
               facet_kinds=counts_of(S.kind, cspace.FACET_KINDS),
               labels_sha=sha(S.labels, np.int64), kind_sha=sha(S.kind, np.int64),
               source_sha=sha(S.source_a, np.int64) + ":" + sha(S.source_b, np.int64),
               polytope=fp_polytope(P))
    return out


def fp_sum_polyhedron(S) -> dict:
    """A ``minkowski_sum`` result (a SumPolyhedron; for a union, its parts too)."""
    out = fp_surface(S)
    out["rounding"] = fls(S.rounding)
    out["convex"] = bool(S.convex)
    if len(getattr(S, "pieces", ())) > 1:  # the union of several bodies' sums
        out["parts"] = [fp_sum_polyhedron(p) for p in S.parts]
        out["pieces"] = [{"vertices_sha": sha(b.vertices, np.float64),
                          "faces_sha": sha(b.faces, np.int64)} for b in S.pieces]
    out.update(
        volume=fl(S.volume), volume_exact=rational(S.volume_exact), holes=int(S.n_holes),
        is_manifold=bool(S.is_manifold), nonmanifold_edges=len(S.nonmanifold_edges),
        nonmanifold_vertices=len(S.nonmanifold_vertices),
        nonmanifold_sha=sha(S.nonmanifold_edges, np.int64) + ":"
        + sha(S.nonmanifold_vertices, np.int64),
        rounding_self_intersections=len(S.rounding_self_intersections),
        facets=int(len(S.facet_kind)), facet_kinds=counts_of(S.facet_kind, cspace.SUPERSET_KINDS),
        face_facet_sha=sha(S.face_facet, np.int64),
        source_sha=sha(S.facet_source_a, np.int64) + ":" + sha(S.facet_source_b, np.int64),
        shells=int(len(S.shell_is_hole)), shell_sha=sha(S.shell, np.int64),
        grid=fp_grid(S.grid),
        stats={k: S.stats[k] for k in sorted(S.stats)
               if k in ("thickened_operands", "superset_facets", "superset_triangles", "n_planes",
                        "candidate_pairs", "cut_pairs", "subfacets", "shells",
                        "membership_tests", "output_triangles")},
    )
    out["stats"]["hull_excess"] = fl(S.stats.get("hull_excess", 0.0))
    return out


def fp_superset(U) -> dict:
    faces, _, _ = U.triangles()
    return {"vertices": len(U.vertices), "facets": int(U.n_facets), "triangles": len(faces),
            "facet_kinds": counts_of(U.kind, cspace.SUPERSET_KINDS),
            "multiplicity_sum": int(np.sum(U.multiplicity)),
            "multiplicity_sha": sha(U.multiplicity, np.int64),
            "ints_sha": sha(U.ints, np.int64), "labels_sha": sha(U.labels, np.int64),
            "facet_indices_sha": sha(U.facet_indices, np.int64),
            "triangles_sha": sha(faces, np.int64), "is_closed": bool(U.is_closed()),
            "error_bound": fl(U.error_bound), "grid": fp_grid(U.grid)}


# --------------------------------------------------------------------------------------
# section 1: sums


def record(out: dict, key: str, make) -> None:
    """``out[key] = make()``, timed on stderr; an exception is recorded as the entry (a case
    that starts failing shows up in ``--compare`` instead of stopping the run)."""
    t0 = time.perf_counter()
    try:
        out[key] = make()
    except Exception as exc:  # noqa: BLE001
        out[key] = {"error": f"{type(exc).__name__}: {exc}"}
        print(f"{key}: {type(exc).__name__}: {exc}", file=sys.stderr)
    print(f"{time.perf_counter() - t0:8.3f} s  {key}", file=sys.stderr, flush=True)


def sum_cases() -> dict:
    """name -> (how, A, B): ``how`` 'convex' (``convex_minkowski_sum``) or 'sum'
    (``minkowski_sum``); A a shared-data path relative to ``SHARED`` is loaded when used."""
    ico80, ico320 = icosphere(1, 0.3), icosphere(2, 0.25)
    cube, cyl = box((0.4, 0.4, 0.4)), cylinder(0.2, 0.5, 12)
    hull20 = hull_points(20, 0.3, seed=7)
    L, T, A = l_prism(), torus(), annulus()
    cases = {
        "cvms/cube+ico80": ("convex", cube[0], ico80[0]),
        "cvms/cylinder12+hull20": ("convex", cyl[0], hull20),
        "cvms/offorigin-ico80+cube": ("convex", moved(ico80[0], OFFSET), moved(cube[0], OFFSET)),
        "cvms/scaled1000-cylinder12+hull20": ("convex", cyl[0] * 1000.0, hull20 * 1000.0),
        "cvms-path/cube+cylinder12": ("sum", cube, cyl[0]),
        "ncc/L+cube": ("sum", L, cube[0]),
        "ncc/L+ico80": ("sum", L, ico80[0]),
        "ncc/L+ico320": ("sum", L, ico320[0]),
        "ncc/torus+ico80": ("sum", T, ico80[0]),
        "ncc/annulus+cylinder12": ("sum", A, cyl[0]),
        "ncc/offorigin-torus+cube": ("sum", moved(T, OFFSET), moved(cube[0], OFFSET)),
        "ncc/scaled0.0375-L+hull20": ("sum", moved(L, scale=0.0375), hull20 * 0.0375),
        "ncc/scaled1000-annulus+ico80": ("sum", moved(A, scale=1000.0), ico80[0] * 1000.0),
        "ncc/L+reflected-ico80": ("sum", L, "reflected"),
        "union/edge-boxes+ico80": ("sum", edge_boxes(), ico80[0]),
    }
    data = {
        "ncc/bunny128+hull20": ("lien_mesh_segmentation/bunny-128.obj", hull20 * 0.1),
        "ncc/yoda658+ico80": ("lien_mesh_segmentation/yoda-658.obj", ico80[0] * 0.1),
        "ncc/bumpy528+cube": ("lien_mesh_unfolder/bumpy-528.obj", cube[0] * 0.2),
        "ncc/trap-genus1+cube": ("parasol_open_ppl_env/bug_trap1.0/trap.obj", cube[0] * 4.0),
    }
    for name, (rel, B) in data.items():
        if (SHARED / rel).is_file():
            cases[name] = ("sum", rel, B)
    return cases


def fp_sum_case(how, A, B) -> dict:
    entry: dict = {}
    if how == "convex":
        PA = cspace.ConvexPolytope.from_points(A, name="A")
        PB = cspace.ConvexPolytope.from_points(B, name="B")
        entry["operands"] = {"A": fp_polytope(PA), "B": fp_polytope(PB)}
        entry["sum"] = fp_minkowski_sum(cspace.convex_minkowski_sum(A, B))
        entry["sum_of_polytopes"] = fp_minkowski_sum(cspace.convex_minkowski_sum(PA, PB))
        return entry
    if isinstance(A, str):
        A = shared_mesh(A)
        entry["operand_A"] = fp_closed_mesh(A)
    if isinstance(B, str) and B == "reflected":
        robot = cspace.ConvexPolytope.from_points(icosphere(1, 0.3)[0], name="robot")
        B = robot.reflected((0.1, 0.2, 0.3))
        entry["operand_B"] = fp_polytope(B)
    S = cspace.minkowski_sum(A, B, workers=1)
    entry["sum"] = fp_sum_polyhedron(S)
    if not S.convex and not hasattr(S, "parts"):
        entry["superset"] = fp_superset(cspace.minkowski_superset(A, B))
    return entry


def run_sums(out: dict) -> None:
    for name, (how, A, B) in sum_cases().items():
        record(out, "sum/" + name, lambda: fp_sum_case(how, A, B))


# --------------------------------------------------------------------------------------
# queries


def sample(bounds, rng, n: int) -> np.ndarray:
    lo, hi = np.asarray(bounds, dtype=np.float64)
    return lo + (hi - lo) * rng.random((n, 3))


def segments(bounds, rng, n: int = N_SEGMENTS, long: int = N_LONG):
    """``n`` random segments in ``bounds``: ``n - long`` local steps (each coordinate within
    10% of the box's extent, as a planner's), then ``long`` across the whole box (a long
    segment through a C-obstacle of 10^5 triangle pairs costs about a second)."""
    lo, hi = np.asarray(bounds, dtype=np.float64)
    q0 = sample(bounds, rng, n)
    step = (hi - lo) * 0.1 * (2.0 * rng.random((n - long, 3)) - 1.0)
    q1 = np.vstack([np.clip(q0[: n - long] + step, lo, hi), sample(bounds, rng, long)])
    return q0, q1


def surface_of(co):
    """Vertices and faces of a C-obstacle, cheaply: for triangle pairs (``kind == 'pairs'``,
    10^5 pieces whose hulls are built only on demand, 0.6 ms each) the hulls of 64 pieces
    drawn with a fixed seed (``sample_mesh``), else all of them."""
    if co.kind == "pairs":
        return co.sample_mesh(np.random.default_rng(5), 64)
    return np.asarray(co.vertices), np.asarray(co.faces)


def boundary_points(cos, limit: int = 40) -> np.ndarray:
    """A few C-obstacle vertices (on the boundary: the exact fallbacks decide them)."""
    pts = []
    for co in cos:
        V = surface_of(co)[0]
        if len(V):
            pts += [V[0], V[len(V) // 2]]
        if len(pts) >= limit:
            break
    return np.array(pts[:limit], dtype=np.float64).reshape(-1, 3)


def attempt(f, encode):
    """``encode(f())``, or the error it raises as text (an error is an output too)."""
    try:
        return encode(f())
    except Exception as exc:  # noqa: BLE001
        return {"error": f"{type(exc).__name__}: {exc}"}


def segment_answers(query, q0, q1, encode):
    """``encode(query(q0, q1))``; when the batch call raises, the error and each segment's
    answer on its own (so that the segments it does answer are still recorded)."""
    out = attempt(lambda: query(q0, q1), encode)
    if isinstance(out, dict):
        out["each"] = [attempt(lambda: query(a, b), repr) for a, b in zip(q0, q1)]
    return out


def hashed(x) -> str:
    return hashlib.sha256(json.dumps(x, sort_keys=True).encode()).hexdigest()


def fp_queries(space, points, q0, q1, per=()) -> dict:
    """Answers of ``space`` (a CSpace or CSpaceObstacle), and hashed per C-obstacle ``per``."""
    p, a, b = points[0], q0[0], q1[0]
    out = {
        "contains": attempt(lambda: space.contains(points), bits),
        "signed_distance": attempt(lambda: space.signed_distance(points), fls),
        "segment_free": segment_answers(space.segment_free, q0, q1, bits),
        "first_contact": segment_answers(space.first_contact, q0, q1, fls),
        "single": {  # the (3,) forms return Python scalars
            "contains": attempt(lambda: space.contains(p), repr),
            "signed_distance": attempt(lambda: space.signed_distance(p), repr),
            "segment_free": attempt(lambda: space.segment_free(a, b), repr),
            "first_contact": attempt(lambda: space.first_contact(a, b), repr),
        },
    }
    if per:
        out["per_obstacle"] = [
            {"contains": hashed(attempt(lambda: co.contains(points), bits)),
             "signed_distance": hashed(attempt(lambda: co.signed_distance(points), fls)),
             "segment_free": hashed(segment_answers(co.segment_free, q0, q1, bits)),
             "first_contact": hashed(segment_answers(co.first_contact, q0, q1, fls))}
            for co in per]
    return out


def fp_cobstacle(co) -> dict:
    V, F = surface_of(co)
    out = {"kind": co.kind, "facets": int(co.n_facets), "vertices": len(V), "faces": len(F),
           "vertices_sha": sha(V, np.float64), "faces_sha": sha(F, np.int64),
           "bounds": fls(co.bounds), "error_bound": fl(co.error_bound), "grid": fp_grid(co.grid),
           "reference_point": fls(co.reference_point)}
    if co.kind == "pairs":  # V, F: a sample of the pieces; the pairs themselves in full
        tp = co.pairs
        out["pairs"] = {"pairs": len(tp.pairs), "pairs_sha": sha(tp.pairs, np.int64),
                        "flat_sha": sha(tp.flat, np.bool_), "S_sha": sha(tp.S, np.int64),
                        "T_sha": sha(tp.T, np.int64), "margin": [int(x) for x in tp.margin],
                        "flat_skipped": int(tp.flat_skipped),
                        "out_of_bounds": int(tp.out_of_bounds)}
    if co.kind == "surface":
        out["pieces"] = len(co.pieces)
    return out


# --------------------------------------------------------------------------------------
# section 2: C-obstacles built directly


def run_cobstacles(out: dict) -> None:
    octa = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]],
                    dtype=np.float64) * 0.25
    cases = {
        "convex/cube+octahedron": (box((1.0, 1.0, 1.0)), octa, (0.05, 0.0, 0.0)),
        "mesh/L+octahedron": (l_prism(), octa, (0.0, 0.1, 0.0)),
        "mesh/offorigin-torus+cube": (moved(torus(), OFFSET), box((0.3, 0.3, 0.3))[0],
                                      tuple(OFFSET)),
        "union/edge-boxes+octahedron": (edge_boxes(), octa, (0.0, 0.0, 0.0)),
    }
    for name, (obstacle, robot, c) in cases.items():
        record(out, "co/" + name, lambda: fp_co_case(obstacle, robot, c))


def fp_co_case(obstacle, robot, c) -> dict:
    entry = {}
    for conservative in (True, False):
        co = cspace.CSpaceObstacle.build(obstacle, robot, c, conservative=conservative)
        rng = np.random.default_rng(11)
        lo, hi = co.bounds
        pad = 0.25 * (hi - lo)
        box_ = np.stack([lo - pad, hi + pad])
        pts = np.vstack([sample(box_, rng, N_POINTS), boundary_points([co])])
        q0, q1 = segments(box_, rng, long=N_SEGMENTS // 2)
        key = "conservative" if conservative else "exact"
        entry[key] = {"cobstacle": fp_cobstacle(co), "queries": fp_queries(co, pts, q0, q1)}
        if co.kind == "convex":
            entry[key]["plane_signs_sha"] = sha(co.plane_signs(pts), np.int8)
    return entry


# --------------------------------------------------------------------------------------
# section 3: scenes


_SECONDS = re.compile(r"\d+(\.\d+)?(e-?\d+)? s\b")


def solids_scene(folder: Path) -> Path | None:
    """A TOML scene of closed non-convex meshes (solid bodies, NCC-CVMS C-obstacles)."""
    bunny = SHARED / "lien_mesh_segmentation" / "bunny-128.obj"
    bumpy = SHARED / "lien_mesh_unfolder" / "bumpy-528.obj"
    octa = ROOT / "scenes" / "meshes" / "octahedron.obj"
    if not (bunny.is_file() and bumpy.is_file() and octa.is_file()):
        return None
    path = folder / "solids.toml"
    path.write_text(f"""name = "solids"
[robot]
mesh = {json.dumps(str(octa))}
scale = 0.3
[planning]
bounds = [[-2.0, -2.0, -2.0], [2.0, 2.0, 2.0]]
start = [-1.9, -1.9, -1.9]
goal = [1.9, 1.9, 1.9]
[[obstacles]]
name = "bunny"
mesh = {json.dumps(str(bunny))}
position = [-0.5, 0.0, 0.0]
[[obstacles]]
name = "bumpy"
mesh = {json.dumps(str(bumpy))}
scale = 0.02
position = [1.2, 0.3, -0.4]
orientation = [0.3, 0.2, 0.1]
[[obstacles]]
name = "plate"
box = [0.2, 1.5, 1.5]
position = [-1.6, 0.0, 0.0]
""")
    return path


def scene_paths(folder: Path) -> dict:
    paths = {p.stem: p for p in sorted((ROOT / "scenes").glob("*.toml"))}
    fcl = ROOT / "scenes" / "shared" / "fcl_env.toml"
    if fcl.is_file() and (SHARED / "fcl_test_resources" / "env.obj").is_file():
        paths["shared/fcl_env"] = fcl
    trap = SHARED / "parasol_open_ppl_env" / "bug_trap1.0" / "bug-trap.env"
    if trap.is_file():
        paths["parasol/bug-trap"] = trap
    solids = solids_scene(folder)
    if solids is not None:
        paths["generated/solids"] = solids
    return paths


def _anonymous(text: str, folder: str) -> str:
    """``text`` without the machine's paths (checkouts and temporary folders differ)."""
    return text.replace(folder, "<tmp>").replace(str(ROOT.parent), "<root>")


def fp_model(m, folder: str) -> dict:
    explain = [_anonymous(_SECONDS.sub("<t> s", line), folder)
               for line in m.explain().splitlines()]
    bodies = []
    for b in m.bodies:
        bodies.append({
            "name": b.name, "source": b.source if "/" not in b.source else Path(b.source).name,
            "kind": b.kind, "reason": _anonymous(b.reason, folder),
            "changed": _anonymous(b.changed, folder), "error": _anonymous(b.error, folder),
            "pieces": int(b.pieces), "vertices_sha": sha(b.vertices, np.float64),
            "faces_sha": sha(b.faces, np.int64), "faces": len(b.faces),
            "cache": b.cache, "co": None if b.co is None else fp_cobstacle(b.co),
            "pairs": [{"part": p.part, "construction": p.construction, "detail": p.detail,
                       "cache": p.cache, "cos": len(p.cos)} for p in b.pairs],
        })
    return {
        "counts": m.counts(), "grid": fp_grid(m.grid), "error_bound": fl(m.error_bound),
        "robot_hull": bool(m.robot_hull),
        "robot": None if m.robot is None else fp_polytope(m.robot),
        "robot_parts": [{"name": p.name, "kind": p.kind, "reason": _anonymous(p.reason, folder),
                         "ints_sha": sha(p.ints, np.int64), "faces_sha": sha(p.faces, np.int64),
                         "grid": fp_grid(p.grid)} for p in m.robot_parts],
        "sources": {k: {kk: int(vv) for kk, vv in sorted(v.items())}
                    for k, v in sorted(m.sources.items())},
        "meaning_changes": m.meaning_changes(),
        "bodies": bodies,
        "explain": explain,
    }


def fp_scene(path: Path, folder: str) -> dict:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = cspace.load_scene(path)
        model = cspace.model_scene(scene, cache=None)
    space = model.cspace()
    rng = np.random.default_rng(2024)
    points = np.vstack([sample(scene.bounds, rng, N_POINTS), boundary_points(space.obstacles),
                        np.stack([scene.start, scene.goal])])
    q0, q1 = segments(scene.bounds, rng)
    q0, q1 = np.vstack([q0, scene.start[None]]), np.vstack([q1, scene.goal[None]])

    def body(b) -> dict:
        return {"name": b.name, "vertices_sha": sha(b.vertices, np.float64),
                "faces_sha": sha(b.faces, np.int64)}

    return {
        "scene": {"name": scene.name, "bounds": fls(scene.bounds), "start": fls(scene.start),
                  "goal": fls(scene.goal), "reference_point": fls(scene.reference_point),
                  "obstacles": [body(b) for b in scene.obstacles], "robot": body(scene.robot),
                  "warnings": sorted({_anonymous(str(w.message), folder) for w in caught})},
        "model": fp_model(model, folder),
        "cspace": {"name": space.name, "obstacles": len(space), "bounds": fls(space.bounds),
                   "robot_hull": bool(space.robot_hull),
                   "cobstacles": [fp_cobstacle(co) for co in space.obstacles]},
        "queries": fp_queries(space, points, q0, q1, per=space.obstacles),
    }


def run_scenes(out: dict) -> None:
    with tempfile.TemporaryDirectory() as folder:
        for name, path in scene_paths(Path(folder)).items():
            record(out, "scene/" + name, lambda: fp_scene(path, folder))


# --------------------------------------------------------------------------------------
# the public API's shape


def _param(p) -> list:
    default = None
    if p.default is not inspect.Parameter.empty:
        default = repr(p.default)
        if " at 0x" in default:
            default = type(p.default).__name__
    return [p.name, p.kind.name, default]


def _signature(f):
    try:
        return [_param(p) for p in inspect.signature(f).parameters.values()]
    except (TypeError, ValueError):
        return None


def fp_api() -> dict:
    out = {"__all__": sorted(cspace.__all__), "__version__": cspace.__version__, "names": {}}
    for name in sorted(cspace.__all__):
        obj = getattr(cspace, name)
        if inspect.isclass(obj):
            entry = {"bases": [c.__name__ for c in obj.__mro__[1:]], "members": {}}
            for attr in sorted(dir(obj)):  # inherited too: moving a method to a base is no change
                if attr.startswith("_") and attr != "__init__":
                    continue
                v = inspect.getattr_static(obj, attr)
                kind = type(v).__name__
                f = v.__func__ if isinstance(v, (classmethod, staticmethod)) else v
                entry["members"][attr] = [kind, _signature(f) if callable(f) else None]
            out["names"][name] = entry
        elif callable(obj):
            out["names"][name] = {"function": _signature(obj)}
        else:
            out["names"][name] = {"value": repr(obj)}
    return out


# --------------------------------------------------------------------------------------
# main, compare


def fingerprint() -> dict:
    out: dict = {"api": fp_api(),
                 "meta": {"numpy": np.__version__, "trimesh": trimesh.__version__,
                          "shared_data": SHARED.is_dir()}}
    t0 = time.perf_counter()
    run_sums(out)
    run_cobstacles(out)
    run_scenes(out)
    print(f"{time.perf_counter() - t0:8.3f} s  total", file=sys.stderr)
    return out


def leaves(x, path=""):
    if isinstance(x, dict):
        for k in sorted(x):
            yield from leaves(x[k], f"{path}.{k}" if path else str(k))
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield from leaves(v, f"{path}[{i}]")
        yield f"{path}.__len__", len(x)
    else:
        yield path, x


def compare(a_path: str, b_path: str, shown: int = 8) -> int:
    a, b = (json.loads(Path(p).read_text()) for p in (a_path, b_path))
    differ = 0
    for key in sorted(set(a) | set(b)):
        if key not in a or key not in b:
            print(f"{key}: only in {a_path if key in a else b_path}")
            differ += 1
            continue
        if a[key] == b[key]:
            continue
        differ += 1
        la, lb = dict(leaves(a[key])), dict(leaves(b[key]))
        va = {p: str(la.get(p, "<missing>")) for p in set(la) | set(lb)}
        vb = {p: str(lb.get(p, "<missing>")) for p in set(la) | set(lb)}
        diffs = [p for p in sorted(va) if va[p] != vb[p]]
        print(f"{key}: {len(diffs)} differing values")
        for p in diffs[:shown]:
            print(f"    {p}: {va[p][:80]} != {vb[p][:80]}")
        if len(diffs) > shown:
            print(f"    ... and {len(diffs) - shown} more")
    print(f"{differ} of {len(set(a) | set(b))} entries differ" if differ else
          f"identical: {len(a)} entries")
    return 1 if differ else 0


def main(argv: list[str]) -> int:
    if argv and argv[0] == "--compare":
        if len(argv) != 3:
            print("usage: fingerprint.py --compare A.json B.json", file=sys.stderr)
            return 2
        return compare(argv[1], argv[2])
    if argv and argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0
    text = json.dumps(fingerprint(), sort_keys=True, indent=1, ensure_ascii=False) + "\n"
    if argv and argv[0] != "-":
        Path(argv[0]).write_text(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
