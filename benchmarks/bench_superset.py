"""Benchmark: the NCC-CVMS superset (step 1) — size and time per case, per stage.

Cases: the test zoo (torus 2304, star 60, comb, grate, L, cup, genus-3, stairs) and the
closed meshes of ``../shared/data`` (bunny, bumpy, yoda, centaur, alpha-puzzle obstacle,
bug-trap) against a box, a 20-facet hull and a 320-facet icosphere (scaled to 8% of A), plus a
10^4-triangle torus against a ~500-facet hull (the issue's scale target).

For scale only, manifold3d's *complete* Minkowski sum of the same pair is timed in the same
run when the ``peers`` extra is installed: it does far more (the trimmed sum), so its column is
context for the later trimming step, not a like-for-like ratio. Every superset is checked to
be a closed 2-cycle before its time is reported; ``chi0`` counts colliding placements (out of
2000 random ones, FCL) where the superset's winding number is 0 because the robot meets A in
a set of Euler characteristic 0 (see tests/test_superset.py).

Usage: ``python benchmarks/bench_superset.py [--quick]``; writes ``benchmarks/reports/superset.md``.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the zoo and the oracles live with the tests

import zoo  # noqa: E402
from oracles import FclSolid, winding_number  # noqa: E402

import cspace  # noqa: E402
from cspace.mesh.convex import ConvexPolytope  # noqa: E402
from cspace.geometry.exact import Grid  # noqa: E402
from cspace.mesh.closed import ClosedMesh  # noqa: E402
from cspace.minkowski.superset import minkowski_superset, reduced_superset  # noqa: E402

try:
    import manifold3d
except ImportError:
    manifold3d = None

REPORT = ROOT / "benchmarks" / "reports" / "superset.md"
SHARED = ROOT.parent / "shared" / "data"


def cases(quick: bool):
    zoo_cases = {
        "torus": zoo.torus(),
        "star": zoo.star(),
        "comb": zoo.comb(),
        "grate": zoo.grate(3),
        "l_shape": zoo.l_shape(),
        "cup": zoo.cup(),
        "genus3": zoo.genus3(),
        "stairs": zoo.stairs(),
    }
    for name, (v, f) in zoo_cases.items():
        for rname, r in zoo.scaled_robots(float(np.ptp(v, axis=0).max())).items():
            yield f"{name} ⊕ {rname}", v, f, r
    if SHARED.is_dir():
        for name, path in zoo.shared_closed_meshes(SHARED).items():
            m = ClosedMesh.load(path)
            for rname, r in zoo.scaled_robots(float(np.ptp(m.vertices, axis=0).max())).items():
                yield f"{name} ⊕ {rname}", m.vertices, m.faces, r
    if not quick:
        v, f = zoo.torus(sections=100, ring=50)
        rng = np.random.default_rng(0)
        p = rng.normal(size=(260, 3))
        p /= np.linalg.norm(p, axis=1)[:, None]
        yield "torus(10000) ⊕ hull(516)", v, f, 0.2 * p


def chi0_count(A, R, S, n=2000, seed=0) -> tuple[int, int]:
    rng = np.random.default_rng(seed)
    lo, hi = S.vertices.min(0), S.vertices.max(0)
    q = rng.uniform(lo, hi, size=(n, 3))
    faces, _, weight = S.triangles()
    w = np.round(winding_number(S.vertices, faces, q, weights=weight)).astype(int)
    cls = FclSolid(A.vertices, A.faces).classify(R.vertices, R.faces, q, band=1e-9)
    off = cls.clearance >= 1e-9
    wrong = off & ~cls.inside & (w != 0)
    if wrong.any():
        raise SystemExit("superset winding is non-zero outside the sum: a bug")
    return int((off & cls.inside & (w == 0)).sum()), int(cls.inside.sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the 10^4-triangle case")
    ap.add_argument("--out", type=Path, default=REPORT)
    args = ap.parse_args()
    rows = []
    for name, v, f, r in cases(args.quick):
        grid = Grid.for_points(v, r)
        A = ClosedMesh.from_arrays(v, f, grid=grid, name=name)
        R = ConvexPolytope.from_points(r, grid=grid, name="robot")
        B = R.reflected((0.0, 0.0, 0.0))
        t = time.perf_counter()
        S = minkowski_superset(A, B)
        total = time.perf_counter() - t
        kinds = np.bincount(S.kind, minlength=3)
        t = time.perf_counter()
        K = reduced_superset(S, A, B)
        t_red = time.perf_counter() - t
        kept = np.bincount(K.kind, minlength=3)
        tri = len(S.triangles()[0])
        t_mf = float("nan")
        if manifold3d is not None and len(A.faces) <= 4000:
            mesh = manifold3d.Mesh(vert_properties=A.vertices.astype(np.float32), tri_verts=A.faces.astype(np.uint32))
            ma = manifold3d.Manifold(mesh)
            mb = manifold3d.Manifold.hull_points(B.vertices)
            t0 = time.perf_counter()
            ma.minkowski_sum(mb).num_tri()
            t_mf = time.perf_counter() - t0
        chi0, inside = chi0_count(A, R, S) if len(A.faces) <= 4000 else (-1, -1)
        rows.append((name, len(A.faces), B.n_facets, S.n_facets, kinds, tri, S.timings, total,
                     kept, t_red, t_mf, chi0, inside))
        print(f"{name:32s} A {len(A.faces):6d} B {B.n_facets:4d} superset {S.n_facets:6d} facets {tri:6d} tris "
              f"{total * 1e3:8.1f} ms  reduced {kept.sum():6d} facets {t_red * 1e3:6.1f} ms  "
              f"manifold3d(full sum) {t_mf * 1e3:9.1f} ms  chi0 {chi0}/{inside}")
    lines = [
        "# NCC-CVMS superset (step 1): size and time",
        "",
        f"Generated by `python benchmarks/bench_superset.py{' --quick' if args.quick else ''}` with cspace "
        f"{cspace.__version__}, numpy {np.__version__}, Python {platform.python_version()}, {os.cpu_count()} cores; "
        "one run per case, in one process. Robots are scaled to 8% of A's extent; B = −robot.",
        "",
        "- Every superset was certified to be a closed oriented 2-cycle (exact, on labels) before being timed here.",
        "- Stages: *prepare* (common grid, normals, edges, perturbation axis), *translated* (exact contributing "
        "vertices), *edge* (exact Gauss-arc crossings), *corner* (multiplicities: dual potential, Banchoff index), "
        "*assemble*, *check* (closedness).",
        "- *reduced*: what the trimming arranges (`superset.reduced_superset`, `docs/trimming.md`): the "
        "facets left once the edge facets of A's reflex edges and the corner facets whose vertex has a "
        "neighbour in front of B's facet are dropped (transl/corner/edge), and the time that takes.",
        "- *manifold3d (full sum)*: manifold3d's complete Minkowski sum of the same pair (float32 input), "
        "for scale only: it includes the trimming that is a later step here.",
        "- *chi0*: of 2000 uniform placements, those in collision (FCL, outside a 1e-9 band) where the superset's "
        "winding number is 0 — the robot meets A in a set of Euler characteristic 0 (a ring around a concave "
        "feature); the winding number of the convolution is that Euler characteristic, so positive winding is "
        "sufficient for collision but not necessary. No placement had non-zero winding outside the sum.",
        "",
        "| case | A tris | B facets | superset facets (transl/corner/edge) | superset tris | prepare | translated | edge | corner | assemble | check | total ms | reduced facets (transl/corner/edge) | reduce ms | manifold3d full sum ms | chi0 / colliding |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, fa, fb, fs, kinds, tri, tm, total, kept, t_red, t_mf, chi0, inside in rows:
        st = " | ".join(f"{tm[k] * 1e3:.1f}" for k in ("prepare", "translated", "edge", "corner", "assemble", "check"))
        lines.append(
            f"| {name} | {fa} | {fb} | {fs} ({kinds[0]}/{kinds[1]}/{kinds[2]}) | {tri} | {st} | {total * 1e3:.1f} | "
            f"{kept.sum()} ({kept[0]}/{kept[1]}/{kept[2]}) | {t_red * 1e3:.1f} | "
            f"{'' if np.isnan(t_mf) else f'{t_mf * 1e3:.1f}'} | {'' if chi0 < 0 else f'{chi0} / {inside}'} |"
        )
    totals = [r[7] for r in rows]
    share = [r[8].sum() / r[3] for r in rows]
    lines += ["", f"Largest superset time: {max(totals):.2f} s; median {np.median(totals) * 1e3:.1f} ms. "
              f"Facets kept by the reduction: median {np.median(share):.0%}, fewest {min(share):.0%} "
              f"({rows[int(np.argmin(share))][0]}).", ""]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
