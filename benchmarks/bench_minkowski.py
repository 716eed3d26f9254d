"""Benchmark: the exact Minkowski sum A ⊕ B (NCC-CVMS, ``cspace.minkowski.sum.minkowski_sum``) against
manifold3d's ``Manifold.minkowski_sum`` on the same snapped operands, one run each.

Cases (issue #4's suite): torus (2304 triangles) ⊕ icosphere (320 facets), torus ⊕ box,
star ⊕ icosphere, comb ⊕ box, and the closed meshes of ``../shared/data`` ⊕ {box, 20-facet
hull, 320-facet icosphere} (robots scaled to 8% of the mesh), plus one case whose superset has
about 40k triangles for the peak-memory line. New cases, not tuned on (issue #30): real
meshes of other families, the Parasol flange obstacle (990 triangles, genus 5) and the three
closed parts of its robot (940, 1042 and 3324 triangles, genus 1 each), and four of CGAL's
data meshes kept in ``benchmarks/data/held_out`` (a snowflake plate with 12 holes, genus 12; a
gear; a tube; a machined block), ⊕ the same three.

Every timed call runs in a fresh subprocess (``--child``): *cold*, the first call there (no
cache of any kind warmed; nothing is compiled at run time), and *warm*, the call after one
other sum in the same process (``--warm``); the child reports its time, the sizes,
cspace's per-stage times (``result.stats``, like the paper's Table I), its volume and its peak
resident set size (``resource.getrusage``). Both tools get the operands snapped to the cspace
grid (manifold3d through ``Mesh64``, float64). manifold3d is a speed peer, not a reference: its
volume error is reported against our exact volume. The machine load (``os.getloadavg``) is
written into the report: other jobs share the cores.

Usage: ``python benchmarks/bench_minkowski.py [--quick] [--families] [--out PATH]``; writes
``benchmarks/reports/minkowski.md`` (``--quick``: three small cases, report to stdout only
unless ``--out`` is given; ``--families``: only the section of issue #51's new families,
``benchmarks/data/new_families``, against manifold3d and CGAL's Nef sum, which it builds
with ``benchmarks/peers/build_cgal.sh`` when Debian's ``libcgal-dev`` is installed).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the zoo lives with the tests

import zoo  # noqa: E402

REPORT = ROOT / "benchmarks" / "reports" / "minkowski.md"
SHARED = ROOT.parent / "shared" / "data"
TIMEOUT = 900  # seconds per child
# cspace's stages (result.stats) in pipeline order, with the paper's Table I columns they
# correspond to: SC superset, MST merge/cancel/triangulate, BI+TI boxes and triangle
# intersections, AC arrangements, BT traversal (+ our exact membership), TR output.
STAGES = ["superset", "planes", "intersections", "arrangements", "traversal", "membership", "output",
          "rounding_check"]


# New meshes (issue #30: other families, not tuned on): a file of ../shared/data or of
# benchmarks/data/held_out (CGAL's data meshes, licences in its SOURCES.md) and, for a
# multi-part file, the closed part with that many triangles (None: the whole file).
FLANGE = SHARED / "parasol_open_ppl_env/flange_1.0"
HELD_OUT = ROOT / "benchmarks" / "data" / "held_out"
NEW_MESHES = {"flange-990": (FLANGE / "obstacle.g", None),
              "flange-part-940": (FLANGE / "robot.g", 940),
              "flange-part-1042": (FLANGE / "robot.g", 1042),
              "flange-part-3324": (FLANGE / "robot.g", 3324),
              "snowflake-1286": (HELD_OUT / "snowflake_50mm.off", None),
              "pinion-1300": (HELD_OUT / "pinion.off", None),
              "pipe-320": (HELD_OUT / "pipe.off", None),
              "oblong-840": (HELD_OUT / "oblong.off", None),
              "part-346": (HELD_OUT / "part.off", None),
              "joint-610": (HELD_OUT / "joint_refined.off", None)}


# Added after the reduced superset (docs/trimming.md), which was found on oblong-840: the bar
# measured on meshes that change did not see.
LATE = ("part-346", "joint-610")


# Issue #51's new families (benchmarks/data/new_families, licences in its SOURCES.md): gears,
# housings, plates, brackets, figures, tools, not tuned on. ``--families`` measures them
# against manifold3d and CGAL in their own section of the report.
FAMILIES_DIR = ROOT / "benchmarks" / "data" / "new_families"
FAMILY_ROBOTS = ("box", "ico320")
#: CGAL (Nef polyhedra: a convex decomposition of A, then a union) gets this many seconds a
#: case, with B the box only.
CGAL_TIMEOUT = 60.0
#: Fresh processes per tool, case and cold/warm in the families' section (its 30 cases, the
#: peers' several seconds each on the icosphere: one run each keeps it within the hour).
FAMILY_REPEAT = 1
FAMILIES_BEGIN, FAMILIES_END = "<!-- families: begin -->", "<!-- families: end -->"


def family_meshes() -> dict:
    """``{name: path}`` of the new-family meshes (name: file stem and triangle count)."""
    out = {}
    for path in sorted(FAMILIES_DIR.glob("*.off")):
        n = int(path.read_text().split(None, 3)[2])
        out[f"{path.stem}-{n}"] = path
    return out


def _is_new(name: str) -> bool:
    return name.split(" ⊕ ")[0] in NEW_MESHES


def _new_mesh(name: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces of a new mesh (a part: split by connectivity after welding)."""
    import trimesh

    from cspace.mesh.files import read_mesh_file

    path, part = NEW_MESHES[name]
    m = read_mesh_file(path)
    if part is None:
        return np.asarray(m.vertices), np.asarray(m.faces)
    whole = trimesh.Trimesh(np.asarray(m.vertices), np.asarray(m.faces), process=True)
    (piece,) = [p for p in whole.split(only_watertight=False) if len(p.faces) == part]
    return np.asarray(piece.vertices), np.asarray(piece.faces)


def case_names(quick: bool) -> list[str]:
    if quick:
        return ["comb ⊕ box", "star ⊕ ico80", "l_shape ⊕ hull20"]
    names = ["torus ⊕ ico320", "torus ⊕ box", "star ⊕ ico320", "comb ⊕ box"]
    for mesh in zoo.SHARED_CLOSED_MESHES:
        if (SHARED / zoo.SHARED_CLOSED_MESHES[mesh]).exists():
            names += [f"{mesh} ⊕ {r}" for r in ("box", "hull20", "ico320")]
    for mesh, (path, _) in NEW_MESHES.items():
        if path.exists():
            names += [f"{mesh} ⊕ {r}" for r in ("box", "hull20", "ico320")]
    return names + ["torus(25600) ⊕ ico320"]


def operands(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A's vertices and faces and B's points for a case name."""
    a, b = name.split(" ⊕ ")
    fixed = {
        "torus ⊕ ico320": (zoo.torus, zoo.icosphere_points(2, radius=0.3)),
        "torus ⊕ box": (zoo.torus, zoo.box_points(0.3, 0.25, 0.2)),
        "star ⊕ ico320": (zoo.star, zoo.icosphere_points(2, radius=0.3)),
        "star ⊕ ico80": (zoo.star, zoo.icosphere_points(1, radius=0.3)),
        "comb ⊕ box": (zoo.comb, zoo.box_points(0.5, 0.5, 0.5)),
        "l_shape ⊕ hull20": (zoo.l_shape, zoo.hull20(0, scale=(0.5, 0.35, 0.25))),
        "torus(25600) ⊕ ico320": (lambda: zoo.torus(sections=160, ring=80), zoo.icosphere_points(2, radius=0.3)),
    }
    if name in fixed:
        build, bp = fixed[name]
        v, f = build()
        return v, f, bp
    from cspace.mesh.closed import ClosedMesh

    families = family_meshes()
    if a in NEW_MESHES:
        v, f = _new_mesh(a)
    elif a in families:
        from cspace.mesh.files import read_mesh_file

        m = read_mesh_file(families[a])
        v, f = np.asarray(m.vertices), np.asarray(m.faces)
    else:
        m = ClosedMesh.load(SHARED / zoo.SHARED_CLOSED_MESHES[a])
        v, f = m.vertices, m.faces
    return v, f, zoo.scaled_robots(float(np.ptp(v, axis=0).max()))[b]


# --------------------------------------------------------------------------------------
# child: one timed call in a fresh process


# The other sum a warm child computes first (with the same tool), so that the timed call
# finds the process, its imports and any lazily built state already in use.
WARMUP_CASE = "comb ⊕ box"


def child(tool: str, name: str, warm: bool = False) -> dict:
    """One timed sum in this (fresh) process: the first call (*cold*), or with ``warm`` the
    call after one other sum (``WARMUP_CASE``, or ``l_shape ⊕ hull20`` when that is the case)."""
    import resource

    if warm:
        child(tool, WARMUP_CASE if name != WARMUP_CASE else "l_shape ⊕ hull20")

    from cspace.mesh.convex import ConvexPolytope
    from cspace.geometry.exact import Grid
    from cspace.mesh.closed import ClosedMesh

    v, f, b = operands(name)
    grid = Grid.for_points(v, b)
    A = ClosedMesh.from_arrays(v, f, grid=grid, name=name)
    B = ConvexPolytope.from_points(b, grid=grid, name="B")
    out: dict = {"tool": tool, "case": name, "a_tris": int(len(A.faces)), "b_facets": int(B.n_facets)}
    if tool == "cspace":
        from cspace.minkowski.sum import minkowski_sum

        t = time.perf_counter()
        S = minkowski_sum(A, B)
        out["time"] = time.perf_counter() - t
        out["tris"] = int(len(S.faces))
        # float of the exact Fraction (its text can exceed Python's 4300-digit limit)
        out["volume"] = repr(float(S.volume_exact))
        out["volume_digits"] = S.volume_exact.denominator.bit_length()
        out["stats"] = {k: (float(v) if isinstance(v, (float, np.floating)) else int(v)) for k, v in S.stats.items()}
        out["n_holes"] = S.n_holes
        out["manifold"] = bool(S.is_manifold)
        out["rounding_self_intersections"] = int(len(S.rounding_self_intersections))
    elif tool == "manifold3d":
        import manifold3d

        # Writable copies: the binding rejects cspace's read-only arrays.
        mesh = manifold3d.Mesh64(
            vert_properties=np.array(A.vertices, dtype=np.float64, order="C"),
            tri_verts=np.array(A.faces, dtype=np.uint64, order="C"),
        )
        MA = manifold3d.Manifold(mesh)
        MB = manifold3d.Manifold.hull_points(np.array(B.vertices, dtype=np.float64, order="C"))
        t = time.perf_counter()
        MS = MA.minkowski_sum(MB)
        n = MS.num_tri()  # forces the lazy result
        out["time"] = time.perf_counter() - t
        out["tris"] = int(n)
        out["volume"] = repr(float(MS.volume()))
        out["status"] = str(MS.status())
    elif tool == "cgal":
        import bench_hard_cases as peers  # the CGAL runner (benchmarks/peers)

        peers.CGAL["binary"] = os.environ["CSPACE_CGAL"]
        kind, got = peers.cgal_sum(np.asarray(A.vertices), np.asarray(A.faces),
                                   -np.asarray(B.vertices), timeout=CGAL_TIMEOUT)
        if kind != "ok":
            out["error"] = got
        else:
            out["time"], out["tris"], out["volume"] = got[2], int(len(got[1])), repr(float(got[3]))
    else:
        raise SystemExit(f"unknown tool {tool!r}")
    out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return out


def run_child(tool: str, name: str, warm: bool = False) -> dict:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", tool, name]
    if warm:
        cmd.append("--warm")
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return {"tool": tool, "case": name, "error": f"timeout after {TIMEOUT} s"}
    if p.returncode != 0:
        last = (p.stderr.strip().splitlines() or ["?"])[-1]
        return {"tool": tool, "case": name, "error": f"exit {p.returncode}: {last}"}
    return json.loads(p.stdout.strip().splitlines()[-1])


# Runs per tool and case (fresh subprocesses); the median is reported. Cases whose first run
# takes longer than REPEAT_BELOW seconds run once (their noise is small against their time).
REPEAT = 3
REPEAT_BELOW = 20.0


def median_child(tool: str, name: str, warm: bool = False) -> dict:
    """The run with the median time of up to REPEAT runs (``runs``: how many)."""
    runs = [run_child(tool, name, warm)]
    if "error" not in runs[0] and runs[0]["time"] < REPEAT_BELOW:
        runs += [run_child(tool, name, warm) for _ in range(REPEAT - 1)]
    ok = sorted((r for r in runs if "error" not in r), key=lambda r: r["time"])
    if not ok:
        return runs[0]
    out = dict(ok[len(ok) // 2])
    out["runs"] = len(ok)
    return out


# --------------------------------------------------------------------------------------
# report


def _fmt_t(x) -> str:
    return "—" if x is None else (f"{x * 1e3:.0f} ms" if x < 1 else f"{x:.2f} s")


def _geomean(xs: list) -> float:
    return math.exp(sum(map(math.log, xs)) / len(xs)) if xs else float("nan")


def report(rows: list[tuple[dict, dict, dict, dict]], load0, load1, quick: bool) -> str:
    import cspace

    try:
        import manifold3d  # noqa: F401
        from importlib.metadata import version

        mver = version("manifold3d")
    except Exception:  # pragma: no cover
        mver = "?"
    try:
        rev = subprocess.run(["git", "-C", str(ROOT), "log", "-1", "--format=%h %s", "--", "cspace"],
                             capture_output=True, text=True, timeout=10).stdout.strip()
    except Exception:  # pragma: no cover
        rev = "?"
    lines = [
        "# Exact Minkowski sum A ⊕ B (NCC-CVMS) against manifold3d",
        "",
        f"cspace at the last commit touching `cspace/`: {rev}.",
        "",
        f"Generated by `python benchmarks/bench_minkowski.py{' --quick' if quick else ''}` with cspace "
        f"{cspace.__version__}, manifold3d {mver}, numpy {np.__version__}, Python {platform.python_version()}, "
        f"{os.cpu_count()} cores shared with other jobs. Machine load (1/5/15 min) at the start "
        f"{load0[0]:.2f} / {load0[1]:.2f} / {load0[2]:.2f}, at the end {load1[0]:.2f} / {load1[1]:.2f} / {load1[2]:.2f}.",
        "",
        f"- Each time is the median of {REPEAT} runs (one run when the first takes over {REPEAT_BELOW:.0f} s), "
        "each in a fresh subprocess: *cold* = the first call there (nothing compiled at run time: cspace's "
        f"kernels are built at install; no cache of any kind warmed), *warm* = the call after one other sum "
        f"({WARMUP_CASE}) in the same process. Operands snapped to the cspace grid for both tools (manifold3d "
        "via `Mesh64`).",
        "- *ratio* = manifold3d time / cspace time (> 1: cspace faster). *superset*: triangles of the reduced "
        "superset after the plane grouping (what the trimming arranges); *out*: output triangles. *RSS*: peak resident set of the subprocess (imports included).",
        "- *vol err*: manifold3d's volume relative to our exact volume (manifold3d is not a reference).",
        "- Both tools use both cores: manifold3d through its thread pool, cspace by forking workers beside the "
        "parent for the triangle-pair intersections, the per-plane arrangements and the rounding check on large "
        "builds (*procs*: processes of those three stages; `minkowski_sum(workers=...)`, `$CSPACE_WORKERS`).",
        "",
        "| case | A tris | B facets | superset tris | cspace out | manifold3d out | cspace cold | manifold3d cold "
        "| ratio cold | cspace warm | manifold3d warm | ratio warm | cspace RSS MB | manifold3d RSS MB | holes "
        "| manifold | manifold3d vol err |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    cold, warm, new_cold, new_warm = [], [], [], []
    late_cold, late_warm = [], []
    for c, m, cw, mw in rows:
        name = c.get("case") or m.get("case")
        if "error" in c:
            lines.append(f"| {name} | | | | cspace failed: {c['error']} |" + " |" * 12)
            continue
        st = c["stats"]
        cells = []
        late = name.split(" ⊕ ")[0] in LATE
        for ours, theirs, keep, also in ((c, m, new_cold if _is_new(name) else cold, late_cold),
                                         (cw, mw, new_warm if _is_new(name) else warm, late_warm)):
            ct, mt = ours.get("time"), theirs.get("time")
            ratio = (mt / ct) if (mt and ct) else None
            if ratio:
                keep.append(ratio)
                if late:
                    also.append(ratio)
            cells.append(f"{_fmt_t(ct)} | {_fmt_t(mt)} | {'' if ratio is None else f'{ratio:.2f}'}")
        vexact = float(c["volume"])
        verr = f"{float(m['volume']) / vexact - 1:+.2e}" if "volume" in m else m.get("error", "—")
        lines.append(
            f"| {name} | {c['a_tris']} | {c['b_facets']} | {st.get('superset_triangles', '')} | {c['tris']} | "
            f"{m.get('tris', '—')} | {cells[0]} | {cells[1]} | "
            f"{c['peak_rss_mb']:.0f} | {m.get('peak_rss_mb', float('nan')):.0f} | {c['n_holes']} | "
            f"{'yes' if c['manifold'] else 'no'} | {verr} |"
        )
    met = all(r and _geomean(r) >= 5 and min(r) >= 1 for r in (cold, warm))
    lines += [
        "",
        f"Geometric-mean ratio (manifold3d / cspace) over {len(cold)} cases: cold **{_geomean(cold):.2f}** "
        f"(slowest relative case {min(cold) if cold else float('nan'):.2f}), warm **{_geomean(warm):.2f}** "
        f"(slowest {min(warm) if warm else float('nan'):.2f}).",
        f"Issue #18's bar — geomean ≥ 5 and no case below 1, cold and warm: **{'met' if met else 'not met'}**.",
        "",
    ]
    if new_cold:
        both_c, both_w = cold + new_cold, warm + new_warm
        met30 = all(r and _geomean(r) >= 8 and min(r) >= 2 for r in (both_c, both_w))
        lines += [
            f"The {len(new_cold)} new cases alone (real meshes of other families, not tuned on: "
            f"{', '.join(NEW_MESHES)}): cold **{_geomean(new_cold):.2f}** (slowest "
            f"{min(new_cold):.2f}), warm **{_geomean(new_warm):.2f}** (slowest {min(new_warm):.2f}). "
            f"The suite and the new cases, {len(both_c)} cases: cold **{_geomean(both_c):.2f}** "
            f"(slowest {min(both_c):.2f}), warm **{_geomean(both_w):.2f}** (slowest {min(both_w):.2f}).",
            f"Issue #30's bar — geomean ≥ 8 and no case below 2 over the suite and the new cases, "
            f"cold and warm: **{'met' if met30 else 'not met'}**.",
            "",
        ]
        if late_cold and late_warm:
            lc, lw = late_cold, late_warm
            lines += [f"The {len(lc)} cases of the meshes added after the trimming's reduced "
                      f"superset, which was found on oblong-840 ({', '.join(LATE)}: not seen by "
                      f"that change): cold **{_geomean(lc):.2f}** (slowest {min(lc):.2f}), warm "
                      f"**{_geomean(lw):.2f}** (slowest {min(lw):.2f}).", ""]
    lines += [
        "## cspace per-stage times (seconds; like the paper's Table I)",
        "",
        "Stages: *superset* (step 1, SC), *planes* (exact plane groups), *intersections* (steps 4–5: boxes and "
        "exact triangle pairs, BI+TI), *arrangements* (steps 2, 3 and 6 in one exact arrangement per plane: merge, "
        "cancel and cut, AC; also the triangulation of every sub-facet, TR), *traversal* (steps 7–16: shells of "
        "sub-facet sides, BT), *membership* (exact classification of cells), *output* (steps 17–18: the facets "
        "between inside and outside, oriented), *rounding_check* (exact re-check of the float64 output).",
        "",
        "*superset facets (kept)*: the convolution's facets, and those the reduced superset keeps (the edge "
        "facets of A's reflex edges and the corner facets B cannot support are dropped; `docs/trimming.md`).",
        "",
        "| case | " + " | ".join(STAGES) + " | total | procs | superset facets (kept) | candidate pairs | "
        "cut pairs | sub-facets | shells |",
        "|---|" + "---|" * (len(STAGES) + 7),
    ]
    for c, *_ in rows:
        if "error" in c:
            continue
        st = dict(c["stats"])
        cells = " | ".join(f"{st[k]:.3f}" if k in st else "" for k in STAGES)
        lines.append(
            f"| {c['case']} | {cells} | {st.get('total', c['time']):.3f} | "
            f"{st.get('intersection_processes', '')}/{st.get('arrangement_processes', '')}/"
            f"{st.get('rounding_processes', '')} | {st.get('superset_facets', '')} "
            f"({st.get('reduced_facets', '')}) | {st.get('candidate_pairs', '')} | "
            f"{st.get('cut_pairs', '')} | {st.get('subfacets', '')} | {st.get('shells', '')} |"
        )
    return "\n".join(lines) + "\n"


def families_report(rows: list, load0, load1, cgal: str, partial: int = 0) -> str:
    """The new families' section: per case cspace, manifold3d (cold and warm) and CGAL."""
    lines = [
        FAMILIES_BEGIN,
        "## New families (issue #51): gears, housings, plates, brackets, figures, tools",
        "",
        f"Generated by `python benchmarks/bench_minkowski.py --families` on {datetime_now()}, "
        f"{os.cpu_count()} cores shared with other jobs; load (1/5/15 min) at the start "
        f"{load0[0]:.2f} / {load0[1]:.2f} / {load0[2]:.2f}, at the end {load1[0]:.2f} / "
        f"{load1[1]:.2f} / {load1[2]:.2f}. Meshes: `benchmarks/data/new_families` (sources, "
        "licences and what each is in its `SOURCES.md`), not tuned on: each first summed by this "
        f"run. Robots as above ({', '.join(FAMILY_ROBOTS)}, scaled to 8% of the mesh). cspace and "
        f"manifold3d timed as above but in {FAMILY_REPEAT} fresh process per cell (no median), "
        f"cold and warm; {cgal}: its exact Nef-polyhedron sum "
        "(`benchmarks/peers/cgal_minkowski.cpp`: a convex decomposition of A, then the union "
        f"of the pieces' sums), one run, with B the box only, stopped after {CGAL_TIMEOUT:.0f} s "
        "(its own time, reading the files excluded). *ratio* = peer time / cspace time.",
        "",
        "| case | A tris | out | cspace cold | manifold3d cold | ratio | cspace warm | "
        "manifold3d warm | ratio | CGAL | ratio CGAL / cspace cold |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    cold, warm, vs_cgal = [], [], []
    for c, m, cw, mw, g in rows:
        name = c.get("case") or m.get("case")
        if "error" in c:
            lines.append(f"| {name} | | cspace failed: {c['error']} |" + " |" * 8)
            continue
        cells = []
        for ours, theirs, keep in ((c, m, cold), (cw, mw, warm)):
            ct, mt = ours.get("time"), theirs.get("time")
            ratio = mt / ct if (ct and mt) else None
            if ratio:
                keep.append(ratio)
            cells.append(f"{_fmt_t(ct)} | {_fmt_t(mt) if mt else theirs.get('error', '—')} | "
                         f"{'' if ratio is None else f'{ratio:.2f}'}")
        if g is None:
            gcell = "– | –"
        elif "time" in g:
            vs_cgal.append(g["time"] / c["time"])
            gcell = f"{_fmt_t(g['time'])} | {g['time'] / c['time']:.1f}"
        else:
            gcell = f"{g.get('error', '?')} | > {CGAL_TIMEOUT / c['time']:.0f}" if "timeout" in g.get(
                "error", "") else f"{g.get('error', '?')} | –"
        lines.append(f"| {name} | {c['a_tris']} | {c['tris']} | {cells[0]} | {cells[1]} | {gcell} |")
    if partial:
        lines += ["", f"**Partial: {len(rows)} of {partial} cases so far** (the run writes the "
                  "section after each case)."]
    lines += [
        "",
        f"Geometric-mean ratio manifold3d / cspace over {len(cold)} cases: cold "
        f"**{_geomean(cold):.2f}** (slowest {min(cold) if cold else float('nan'):.2f}), warm "
        f"**{_geomean(warm):.2f}** (slowest {min(warm) if warm else float('nan'):.2f}). CGAL "
        f"answered {len(vs_cgal)} of {sum(1 for r in rows if r[4] is not None)} box cases within "
        f"{CGAL_TIMEOUT:.0f} s" + (f", at {_geomean(vs_cgal):.0f}x cspace's cold time in geometric "
                                   f"mean" if vs_cgal else "") + ".",
        FAMILIES_END,
    ]
    return "\n".join(lines) + "\n"


def datetime_now() -> str:
    import datetime

    return datetime.date.today().isoformat()


def _with_section(text: str, section: str) -> str:
    """``text`` with its families section replaced by ``section`` (appended when absent)."""
    if FAMILIES_BEGIN in text:
        head, rest = text.split(FAMILIES_BEGIN, 1)
        tail = rest.split(FAMILIES_END, 1)[1].lstrip("\n") if FAMILIES_END in rest else ""
        return head.rstrip("\n") + "\n\n" + section + ("\n" + tail if tail else "")
    return text.rstrip("\n") + "\n\n" + section


def families(out: Path) -> None:
    """``--families``: the new families' section of the report (see :func:`families_report`)."""
    names = [f"{mesh} ⊕ {r}" for mesh in family_meshes() for r in FAMILY_ROBOTS]
    cgal = "CGAL (not built)"
    try:
        built = subprocess.run(["sh", str(ROOT / "benchmarks" / "peers" / "build_cgal.sh")],
                               capture_output=True, text=True, timeout=1800)
        if built.returncode == 0:
            os.environ["CSPACE_CGAL"] = built.stdout.strip().splitlines()[-1]
            import bench_hard_cases as peers

            cgal = f"CGAL {peers._cgal_version()}"
    except (OSError, subprocess.TimeoutExpired):
        pass
    load0, rows = os.getloadavg(), []

    def one(tool: str, name: str, warm: bool = False) -> dict:
        runs = [run_child(tool, name, warm) for _ in range(FAMILY_REPEAT)]
        ok = sorted((r for r in runs if "error" not in r), key=lambda r: r["time"])
        return dict(ok[len(ok) // 2]) if ok else runs[0]

    def write(partial: int) -> None:
        section = families_report(rows, load0, os.getloadavg(), cgal, partial)
        text = out.read_text() if out.exists() else ""
        tmp = out.with_suffix(".tmp")
        tmp.write_text(_with_section(text, section))
        tmp.replace(out)  # never a half-written report

    for name in names:
        c = one("cspace", name)
        m = one("manifold3d", name)
        cw = one("cspace", name, warm=True)
        mw = one("manifold3d", name, warm=True)
        g = (run_child("cgal", name) if "CSPACE_CGAL" in os.environ and name.endswith("⊕ box")
             else None)
        rows.append((c, m, cw, mw, g))
        print(f"{name:40s} cspace {_fmt_t(c.get('time')):>8s} / {_fmt_t(cw.get('time')):>8s} "
              f"manifold3d {_fmt_t(m.get('time')):>8s} / {_fmt_t(mw.get('time')):>8s} "
              f"CGAL {_fmt_t((g or {}).get('time'))} {(g or {}).get('error', '')} "
              f"{c.get('error', '')} {m.get('error', '')}", flush=True)
        write(len(names) if len(rows) < len(names) else 0)
    print(f"wrote {out}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="three small cases (smoke run)")
    ap.add_argument("--out", type=Path, default=None, help=f"report path (default {REPORT}, or none with --quick)")
    ap.add_argument("--families", action="store_true",
                    help="only the new families' section (issue #51), with CGAL when it builds")
    ap.add_argument("--child", nargs=2, metavar=("TOOL", "CASE"), help=argparse.SUPPRESS)
    ap.add_argument("--warm", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(*args.child, warm=args.warm)))
        return
    if args.families:
        families(args.out or REPORT)
        return
    load0 = os.getloadavg()
    names = case_names(args.quick)
    rows = []
    for name in names:
        c = median_child("cspace", name)
        m = median_child("manifold3d", name)
        cw = median_child("cspace", name, warm=True)
        mw = median_child("manifold3d", name, warm=True)
        rows.append((c, m, cw, mw))
        print(f"{name:32s} cspace {_fmt_t(c.get('time')):>10s} / {_fmt_t(cw.get('time')):>10s} "
              f"({c.get('peak_rss_mb', 0):.0f} MB) manifold3d {_fmt_t(m.get('time')):>10s} / "
              f"{_fmt_t(mw.get('time')):>10s} {c.get('error', '')} {m.get('error', '')}", flush=True)
    text = report(rows, load0, os.getloadavg(), args.quick)
    out = args.out if args.out is not None else (None if args.quick else REPORT)
    if out is None:
        print(text)
    else:
        out.parent.mkdir(parents=True, exist_ok=True)
        old = out.read_text() if out.exists() else ""
        if FAMILIES_BEGIN in old and FAMILIES_END in old:  # kept: --families writes it
            text = _with_section(text, FAMILIES_BEGIN + old.split(FAMILIES_BEGIN, 1)[1].split(
                FAMILIES_END, 1)[0] + FAMILIES_END + "\n")
        out.write_text(text)
        print(f"wrote {out}")


if __name__ == "__main__":
    main()
