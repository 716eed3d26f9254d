"""Benchmark: numerical stability on hard inputs, cspace against manifold3d, exact references.

Families (parameter swept per table):

- *offset*: an L bracket (voxels of 0.5) and a box robot 0.3 x 0.3 x 0.3, both moved by 10^k;
- *scale*: the same, scaled by 10^k;
- *thin*: the L flattened to a plate 10^-k thick (unit scene; 10^-300 included);
- *flat robot*: the L against a panel, a rod (zero thickness on one or two axes);
- *touching*: two boxes sharing an edge or a vertex, as one mesh;
- *tilt*: a prism whose top dips by 10^-k along its middle (two nearly coplanar faces); its
  exact reference is two convex polygons in (x, z) extruded along y (``tests/hard.py``);
- *parallel structure and high genus*: stairs, and a 10 x 10 grate (genus 100);
- *gap comb*: a comb whose slots are exactly as wide as the robot, turned by irrational angles
  (``tests/hard.py``); 101 known collisions along a slot, pushed 1e-9 into a tooth.

References (never manifold3d): every obstacle but the comb is a union of axis-aligned voxels
and the robot an axis-aligned box, so the exact C-obstacle of the *float input* is a union of
boxes ``[cell_lo - r_hi, cell_hi - r_lo]`` computed in exact rationals from the input floats;
membership is decided on it exactly (Fractions), its volume exactly (inclusion-exclusion on
the grid of box bounds). The comb's collisions are known by construction (and confirmed by
FCL in ``tests/test_hard.py``).

Per row: the result or the named error, build seconds, the stated bound (cspace:
``co.error_bound``), the relative volume error, and on 4000 samples (half uniform in the
grown box, half on the reference boundary moved by ``±10^U(-12,-1)`` of the scene size or not
at all) the *false free* (declared free, truly colliding: unsafe) and *false collision* counts
with the largest distance of a false collision from the reference. manifold3d gets the same
float input; its output is queried exactly on its own float64 surface (cspace's exact mesh
queries), so a disagreement is its construction's, not the query's. CGAL's exact Nef
``minkowski_sum_3`` (``benchmarks/peers``, built when the headers are present, else its rows
are left out with the reason) gets the same float input as OFF; its volume is exact, its
surface is rounded to float64 for the membership counts.

Usage: ``python benchmarks/bench_hard_cases.py [--quick] [--no-cgal] [--out PATH]`` writes
``benchmarks/reports/hard_cases.md`` (``--quick``: fewer parameters, stdout unless ``--out``).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from fractions import Fraction
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import hard  # noqa: E402
import zoo  # noqa: E402

import cspace  # noqa: E402
from cspace import CSpaceObstacle  # noqa: E402

REPORT = ROOT / "benchmarks" / "reports" / "hard_cases.md"
RESULTS: list = []  # (family, parameter, tool, row) of every voxel-family row, for the summary
L_OCC = zoo.l_shape(arm=2)  # noqa: F841 (documentation: the same L as the tests)


def _volume_exact(V: np.ndarray, F: np.ndarray) -> Fraction:
    """Exact enclosed volume of a float triangle surface (six-volume sum on rationals)."""
    total = Fraction(0)
    for a, b, c in V[F].tolist():
        A = [Fraction(x) for x in a]
        B = [Fraction(x) for x in b]
        C = [Fraction(x) for x in c]
        total += (A[0] * (B[1] * C[2] - B[2] * C[1]) - A[1] * (B[0] * C[2] - B[2] * C[0])
                  + A[2] * (B[0] * C[1] - B[1] * C[0]))
    return total / 6


def _judge(case: hard.VoxelCase, contains, q: np.ndarray,
           ref: np.ndarray) -> tuple[int, int, float]:
    ours = contains(q)
    false_free = int((~ours & ref).sum())
    fc = ours & ~ref
    far = float(case.distance(q[fc]).max()) if fc.any() else 0.0
    return false_free, int(fc.sum()), far


def _cspace_row(case: hard.VoxelCase, q, ref, vol_ref, conservative=True) -> dict:
    t = time.perf_counter()
    try:
        co = CSpaceObstacle.build((case.vertices, case.faces), case.robot,
                                  conservative=conservative)
    except cspace.CspaceError as exc:
        return {"result": f"{type(exc).__name__}: {str(exc)[:90]}",
                "seconds": time.perf_counter() - t}
    dt = time.perf_counter() - t
    ff, fc, far = _judge(case, co.contains, q, ref)
    if co.kind == "union":
        vol = None
    else:
        vol = _volume_exact(co.vertices, co.faces) if co.kind == "mesh" else Fraction(
            co.polytope.volume6()) / 6 * Fraction(2) ** (3 * co.grid.exponent)
    return {"result": f"ok ({co.kind})", "seconds": dt, "bound": co.error_bound,
            "vol_err": None if vol is None else abs(float((vol - vol_ref) / vol_ref)),
            "false_free": ff, "false_coll": fc, "far": far}


def _manifold_sum(V, F, robot, conn) -> None:
    """Child process: manifold3d's O ⊕ (-R), sent back as arrays (or the error)."""
    try:
        import manifold3d

        MA = manifold3d.Manifold(manifold3d.Mesh64(
            vert_properties=np.ascontiguousarray(V, np.float64),
            tri_verts=np.ascontiguousarray(F, np.uint64)))
        if MA.status() != manifold3d.Error.NoError:
            conn.send(("refused", f"refused: {MA.status().name}"))
            return
        MB = manifold3d.Manifold.hull_points(np.ascontiguousarray(-robot, np.float64))
        t = time.perf_counter()
        out = MA.minkowski_sum(MB).to_mesh64()
        dt = time.perf_counter() - t
        conn.send(("ok", (np.asarray(out.vert_properties, np.float64)[:, :3].copy(),
                          np.asarray(out.tri_verts, np.int64).copy(), dt)))
    except Exception as exc:  # noqa: BLE001 - a peer's failure is a row
        conn.send(("error", f"{type(exc).__name__}: {str(exc)[:80]}"))


def manifold_sum(V, F, robot):
    """``('ok', (V, F, seconds))`` or ``(kind, message)``; in a forked child, because
    manifold3d can take the process down (it does at scale 1e-100)."""
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    parent, child = ctx.Pipe(duplex=False)
    p = ctx.Process(target=_manifold_sum, args=(V, F, robot, child))
    p.start()
    child.close()
    try:
        got = parent.recv() if parent.poll(120) else ("hang", "no answer in 120 s")
    except EOFError:
        got = None
    p.join(5)
    if p.is_alive():
        p.kill()
        p.join()
    if got is None:
        return ("crash", f"process died (exit code {p.exitcode})")
    return got


def _manifold_row(case: hard.VoxelCase, q, ref, vol_ref) -> dict:
    try:
        import manifold3d  # noqa: F401
    except ImportError:
        return {"result": "manifold3d not installed (pip install -e '.[peers]')"}
    kind, got = manifold_sum(case.vertices, case.faces, case.robot)
    if kind != "ok":
        return {"result": got}
    V, F, dt = got
    if not len(F):
        return {"result": "empty result", "seconds": dt}
    try:
        co = CSpaceObstacle.from_mesh(V, F)
    except cspace.CspaceError as exc:
        return {"result": f"invalid output ({type(exc).__name__})", "seconds": dt}
    ff, fc, far = _judge(case, co.contains, q, ref)
    vol = _volume_exact(V, F)
    return {"result": "ok", "seconds": dt, "bound": None,
            "vol_err": abs(float((vol - vol_ref) / vol_ref)), "false_free": ff,
            "false_coll": fc, "far": far}


CGAL = {"binary": None, "status": "not built"}


def _build_cgal() -> None:
    import subprocess

    try:
        out = subprocess.run(["sh", str(ROOT / "benchmarks" / "peers" / "build_cgal.sh")],
                             capture_output=True, text=True, timeout=1800)
    except (OSError, subprocess.TimeoutExpired) as exc:
        CGAL["status"] = f"not built: {exc}"
        return
    if out.returncode:
        CGAL["status"] = "not built: " + (out.stderr.strip().splitlines() or ["?"])[-1]
        return
    CGAL["binary"] = out.stdout.strip().splitlines()[-1]
    CGAL["status"] = "CGAL " + _cgal_version()


def _cgal_version() -> str:
    try:
        text = Path("/usr/include/CGAL/version.h").read_text()
        return text.split("#define CGAL_VERSION ")[1].split()[0]
    except (OSError, IndexError):
        return "(version unknown)"


def _write_off(path: Path, V: np.ndarray, F: np.ndarray) -> None:
    lines = ["OFF", f"{len(V)} {len(F)} 0"]
    lines += [" ".join(repr(float(x)) for x in v) for v in V]
    lines += ["3 " + " ".join(str(int(i)) for i in f) for f in F]
    path.write_text("\n".join(lines) + "\n")


def _read_off(path: Path):
    tok = path.read_text().split()
    nv, nf = int(tok[1]), int(tok[2])
    V = np.array(tok[4:4 + 3 * nv], dtype=np.float64).reshape(nv, 3)
    F = np.array(tok[4 + 3 * nv:], dtype=np.int64).reshape(nf, 4)[:, 1:]
    return V, F


def cgal_sum(V: np.ndarray, F: np.ndarray, robot: np.ndarray, timeout: float = 300.0):
    """CGAL's exact Nef ``O ⊕ (-R)`` of the float input (``CGAL['binary']``, built by
    :func:`_build_cgal`): ``('ok', (V, F, seconds, volume))`` with the boundary rounded to
    float64 and the exact volume (a Fraction), or ``(kind, message)`` when it was not run,
    refused or timed out."""
    import subprocess
    import tempfile

    from scipy.spatial import ConvexHull, QhullError

    B = -robot
    try:  # Qhull on coordinates scaled to about 1 (it has no hull at 1e-100 or 1e100)
        H = ConvexHull((B - B.mean(axis=0)) / np.ptp(B, axis=0).max())
    except QhullError:
        return ("not run", "not run: B has no volume (a Polyhedron_3 operand must be solid)")
    T = H.simplices.copy()
    centre = B[H.vertices].mean(axis=0)
    n = np.cross(B[T[:, 1]] - B[T[:, 0]], B[T[:, 2]] - B[T[:, 0]])
    inward = np.einsum("kj,kj->k", n, B[T[:, 0]] - centre) < 0
    T[inward] = T[inward][:, ::-1]
    with tempfile.TemporaryDirectory() as tmp:
        a, b, o = Path(tmp) / "a.off", Path(tmp) / "b.off", Path(tmp) / "out.off"
        _write_off(a, V, F)
        _write_off(b, B, T)
        try:
            run = subprocess.run([CGAL["binary"], str(a), str(b), str(o)], capture_output=True,
                                 text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return ("timeout", f"no answer in {timeout:.0f} s")
        if run.returncode:
            why = (run.stderr.strip().splitlines() or [f"exit {run.returncode}"])[-1]
            return ("refused", f"refused: {why.split(': ', 1)[-1][:80]}")
        words = run.stdout.split()
        dt, vol = float(words[1]), Fraction(words[3])
        Vo, Fo = _read_off(o)
    return ("ok", (Vo, Fo, dt, vol))


def _cgal_row(case: hard.VoxelCase, q, ref, vol_ref, timeout: float = 300.0) -> dict:
    kind, got = cgal_sum(case.vertices, case.faces, case.robot, timeout)
    if kind != "ok":
        return {"result": got}
    V, F, dt, vol = got
    try:
        co = CSpaceObstacle.from_mesh(V, F)
    except cspace.CspaceError as exc:
        return {"result": f"output invalid after rounding ({type(exc).__name__})", "seconds": dt}
    ff, fc, far = _judge(case, co.contains, q, ref)
    return {"result": "ok", "seconds": dt, "vol_err": abs(float((vol - vol_ref) / vol_ref)),
            "false_free": ff, "false_coll": fc, "far": far}


def _fmt(x, spec=".2g") -> str:
    if x is None:
        return "–"
    if isinstance(x, float):
        return format(x, spec)
    return str(x)


HEAD = ("| parameter | tool | result | seconds | stated bound | volume error | false free | "
        "false collision | farthest false collision |\n|---|---|---|---|---|---|---|---|---|")


def _lines(param: str, rows: list) -> list[str]:
    out = []
    for tool, r in rows:
        out.append(f"| {param} | {tool} | {r['result']} | {_fmt(r.get('seconds'), '.3f')} | "
                   f"{_fmt(r.get('bound'))} | {_fmt(r.get('vol_err'))} | "
                   f"{_fmt(r.get('false_free'))} | {_fmt(r.get('false_coll'))} | "
                   f"{_fmt(r.get('far'))} |")
    return out


def voxel_family(title: str, params, make, n: int, rng) -> list[str]:
    lines = [f"## {title}", "", HEAD]
    for label, case in ((p, make(p)) for p in params):
        q = case.samples(n, rng)
        ref = case.contains(q)
        vol = case.volume()
        rows = [("cspace", _cspace_row(case, q, ref, vol)),
                ("cspace, conservative=False", _cspace_row(case, q, ref, vol, False)),
                ("manifold3d", _manifold_row(case, q, ref, vol))]
        if CGAL["binary"]:
            rows.append(("CGAL Nef", _cgal_row(case, q, ref, vol)))
        lines += _lines(label, rows)
        RESULTS.extend((title, label, tool, r) for tool, r in rows)
        print(title, label, [r["result"] for _, r in rows], flush=True)
    return lines + [""]


def gap_family(angles) -> list[str]:
    lines = ["## Gap comb (slot exactly as wide as the robot, turned)", "",
             "False free among 101 known collisions per angle (``contains``), plus the slot's "
             "``segment_free`` and ``first_contact`` (3 answers more per angle).", "",
             "| tool | angles | false free (of 104 per angle) | angles with any | seconds |",
             "|---|---|---|---|---|"]
    for tool in ("cspace", "cspace, conservative=False", "manifold3d"):
        bad, cracked, secs = 0, 0, 0.0
        for a in angles:
            case = hard.gap_comb(a)
            t = time.perf_counter()
            if tool == "manifold3d":
                kind, got = manifold_sum(*case.obstacle, case.robot)
                if kind != "ok":
                    bad, cracked = f"{kind}: {got}", len(angles)
                    break
                co = CSpaceObstacle.from_mesh(got[0], got[1])
            else:
                co = CSpaceObstacle.build(case.obstacle, case.robot,
                                          conservative=tool == "cspace")
            secs += time.perf_counter() - t
            q = case.colliding
            n = int((~co.contains(q)).sum()) + bool(co.segment_free(q[0], q[-1]))
            n += bool(co.first_contact(q[0], q[-1]) != 0.0)
            bad += n
            cracked += n > 0
        lines.append(f"| {tool} | {len(angles)} | {bad} | {cracked} | {secs:.2f} |")
        RESULTS.append(("gap comb", f"{len(angles)} angles", tool,
                        {"result": "ok" if isinstance(bad, int) else bad,
                         "false_free": bad if isinstance(bad, int) else None}))
    return lines + [""]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", type=Path)
    ap.add_argument("--no-cgal", action="store_true", help="skip the CGAL peer")
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    n = 1000 if args.quick else 4000
    if not args.no_cgal:
        _build_cgal()
    L, cell, robot = hard.l_cells(), (0.5, 0.5, 0.5), (0.3, 0.3, 0.3)
    offsets = [0, 6] if args.quick else [0, 3, 5, 6, 9, 12]
    scales = [-100, 0] if args.quick else [-100, -10, 0, 10, 100]
    thin = [3, 9] if args.quick else [3, 6, 7, 8, 9, 12, 300]
    t0 = time.perf_counter()
    body = []
    body += voxel_family("Offset: L bracket and box robot moved by 10^k",
                         [f"10^{k}" for k in offsets],
                         lambda p: hard.VoxelCase(L, cell, robot,
                                                  lambda x, k=int(p[3:]): x + 10.0 ** k),
                         n, rng)
    body += voxel_family("Scale: L bracket and box robot scaled by 10^k",
                         [f"10^{k}" for k in scales],
                         lambda p: hard.VoxelCase(L, cell, robot,
                                                  lambda x, k=int(p[3:]): x * 10.0 ** k),
                         n, rng)
    body += voxel_family("Thin: the L as a plate 10^-k thick", [f"10^-{k}" for k in thin],
                         lambda p: hard.VoxelCase(L, (0.5, 0.5, 10.0 ** -int(p[4:])), robot),
                         n, rng)
    body += voxel_family("Slivers: the L with 8 cap triangles (`hard.with_caps`)",
                         ["zero area", "1e-12 outwards", "1e-12 outwards, at 10^5"],
                         lambda p: hard.VoxelCase(
                             L, cell, robot, caps=8, lift=0.0 if p == "zero area" else 1e-12,
                             transform=(lambda x: x + 1e5) if p.endswith("10^5") else
                             (lambda x: x)), n, rng)
    body += voxel_family("Flat robot against the L", ["panel (z = 0)", "rod (along x)"],
                         lambda p: hard.VoxelCase(L, cell, (0.3, 0.3, 0.0) if p.startswith("panel")
                                        else (0.3, 0.0, 0.0)), n, rng)
    edge = np.zeros((2, 2, 1), bool)
    edge[0, 0, 0] = edge[1, 1, 0] = True
    vertex = np.zeros((2, 2, 2), bool)
    vertex[0, 0, 0] = vertex[1, 1, 1] = True
    body += voxel_family("Touching: two boxes sharing an edge or a vertex, one mesh",
                         ["edge", "vertex"],
                         lambda p: _touching(edge if p == "edge" else vertex, robot), n, rng)
    tilts = [3, 15] if args.quick else [3, 6, 9, 12, 15]
    body += voxel_family("Tilt: a valley 10^-k deep (two top faces nearly coplanar)",
                         [f"10^-{k}" for k in tilts],
                         lambda p: hard.TiltCase(10.0 ** -int(p[4:])), n, rng)
    shapes = {"stairs (4 steps)": zoo.stairs_occupancy(4, 1)}
    if not args.quick:
        shapes["grate 10 x 10 (genus 100)"] = zoo.grate_occupancy(10)
    body += voxel_family("Parallel structure and high genus (voxels of 0.5, box robot 0.3)",
                         list(shapes), lambda p: hard.VoxelCase(shapes[p], cell, robot),
                         n, rng)
    body += gap_family(hard.GAP_ANGLES[:8] if args.quick else hard.GAP_ANGLES)
    total = time.perf_counter() - t0
    try:
        from importlib.metadata import version

        mver = version("manifold3d")
    except Exception:  # noqa: BLE001
        mver = "absent"
    head = [
        "# Hard cases: numerical stability against exact references",
        "",
        f"Generated by `python benchmarks/bench_hard_cases.py{' --quick' if args.quick else ''}` "
        f"with cspace {cspace.__version__}, manifold3d {mver}, numpy {np.__version__}, Python "
        f"{platform.python_version()}, on {os.cpu_count()} CPUs; load average before "
        f"{os.getloadavg()[0]:.2f}; {total:.0f} s in all.",
        "",
        "- References are exact for the float input (unions of boxes in rationals; see the "
        "script's docstring), never manifold3d. *false free*: declared free, truly colliding "
        "(unsafe for a planner); *false collision*: declared colliding, truly free, with the "
        "farthest such sample's distance from the true C-obstacle (must stay within the stated "
        "bound for cspace). Samples: "
        f"{n}, half on the reference boundary moved by ±10^U(-12,-1) of the scene size.",
        "- *cspace*: `CSpaceObstacle.build` (outward rounding: `cspace.cobstacle.margin`). "
        "*conservative=False*: the exact C-obstacle of the snapped input, no growth (two-sided). "
        "Volume error: of the stored C-obstacle (exact volume of its float surface or polytope) "
        "against the reference's exact volume; '–' where it is a union of several.",
        f"- CGAL: `minkowski_sum_3` on exact Nef polyhedra (`benchmarks/peers/cgal_minkowski.cpp`, "
        f"built by `build_cgal.sh`; {CGAL['status']}), queried like manifold3d on its output "
        "rounded to float64; its volume is exact. It needs a closed 2-manifold operand and a "
        "solid B (touching and flat-robot rows refused).",
        "- Offsets: the grid is centred on what is modelled (`Grid.origin`), so the stated bound "
        "stays that of the unit scene until float64 itself is coarser (the step is never below "
        "2 ulps of the coordinates: at 10^9 and 10^12 the bound follows the floats' spacing). "
        "Thin: a closed obstacle thinner than a grid step is answered by its surface, one "
        "grown convex piece per triangle (`kind='union'`), since the robot, thicker than the "
        "plate, can never lie inside it (a robot that could fit inside also gets the "
        "containment term of the snapped surface's winding number).",
        "- Slivers: eight edges of the L split at their midpoints by a cap triangle of zero "
        "area (or moved 1e-12 outwards, so that snapping flattens it): the repair of "
        "`ClosedMesh` keeps the solid. Turned slivers that snapping folds through the surface "
        "are in the metamorphic sweep (`folded closed body`, `folded closed robot`).",
        "",
    ]
    text = "\n".join(head + summary() + body)
    if args.out or not args.quick:
        path = args.out or REPORT
        # The metamorphic sweep's section is bench_metamorphic.py's: kept as it is.
        old = path.read_text() if path.exists() else ""
        kept = old.find("## Metamorphic sweep")
        text += "" if kept < 0 else "\n" + old[kept:].rstrip("\n")
        tmp = path.with_suffix(".tmp")
        tmp.write_text(text + "\n")
        tmp.replace(path)  # atomic: never a half-written report
        print(f"wrote {path}")
    else:
        print(text)


def summary() -> list[str]:
    """Per tool: rows answered, refused or failed, rows with a false free, and (cspace) the
    largest ratio of a false collision's distance to the stated bound."""
    out = ["## Summary", "", "| tool | rows | answered | refused / failed | rows with false free | "
           "false free answers | worst false collision / stated bound |",
           "|---|---|---|---|---|---|---|"]
    for tool in ("cspace", "cspace, conservative=False", "manifold3d", "CGAL Nef"):
        rows = [r for _, _, t, r in RESULTS if t == tool]
        if not rows:
            continue
        ok = [r for r in rows if str(r["result"]).startswith("ok")]
        ff = [r for r in ok if r.get("false_free")]
        ratio = [r["far"] / r["bound"] for r in ok if r.get("bound") and r.get("far") is not None]
        worst = f"{max(ratio):.2f}" if ratio and tool != "manifold3d" else "–"
        out.append(f"| {tool} | {len(rows)} | {len(ok)} | {len(rows) - len(ok)} | {len(ff)} | "
                   f"{sum(r.get('false_free') or 0 for r in ok)} | {worst} |")
    refused = sorted({f"{fam.split(':')[0]} {p}" for fam, p, t, r in RESULTS
                      if t == "cspace" and not str(r["result"]).startswith("ok")})
    out += ["", "cspace refuses (named error): " + (", ".join(refused) if refused else "nothing")
            + ". With `conservative=False` (the exact sum of the snapped input) false free answers "
            "appear wherever snapping opened space; the outward rounding removes every one of them "
            "at the price of false collisions within the stated bound.", ""]
    return out


def _touching(occ, robot) -> hard.VoxelCase:
    return hard.VoxelCase(occ, (0.5, 0.5, 0.5), robot)


if __name__ == "__main__":
    main()
