"""A whole scene's model, and its convex C-obstacles, as one cache entry: a *snapshot*.

Modelling a body (welding, the convexity proof, classification) costs tens of microseconds,
and making its C-obstacle from its own cache entry (key, read, digest) as much again: a
cached load of 10^4 bodies took 1.3 s, nearly all of it per body. A snapshot is one entry
per scene build, under one key over the scene's whole input (:func:`snapshot_key`); a later
build of the same input restores every body from a few concatenated arrays instead of
modelling it again.

What a snapshot holds, per modelled body in :func:`cspace.scene.model.model_scene`'s order:

- **restored** (a convex body whose polytope is exactly its snapped mesh's hull, no
  ``excess``): its welded grid integers, triangles, reason and polytope; when the
  robot is one convex part, its C-obstacle's polytope too (what a
  per-pair cache entry holds, assembled the same way: :func:`cspace.scene.build._assemble`);
- **a solid** (a closed, non-convex 2-manifold that does not meet itself): its welded grid
  integers and triangles, its reason, and the validated mesh (welded, oriented, its shells),
  restored without the checks that made it (validation and the self-intersection test, a
  few milliseconds per body: at 10^4 boxes and 200 L-shapes they were most of a cached load);
  its C-obstacles come through their per-pair entries;
- **classified again** (every other classified body: surface, a convex hull that stands for a
  bent body, one dropped by the bounds): its welded grid integers, triangles and whether it is
  a double-sided sheet; :func:`cspace.scene.classify._classify` decides it again on restore
  and its C-obstacles come through their per-pair entries (such bodies are few, and their
  builds dear);
- **what snapping took** (a ``<body> (snapped)`` body: segments and points thinner than the
  step, and the region a closed body's 2-cycle encloses when a part lost its inside): its
  grid integers, degenerate triangles, reason and the enclosed region's triangles, restored by
  :func:`cspace.scene.classify._snapped_model` as the build made it;
- **dropped before classification** (far parts): name and reason.

Also: the grid, the scene's margin and per scene body what welding dropped. The key covers
everything these depend on (the bodies' names, float64 vertices and triangles, the robot,
reference point, bounds, the options, cspace's version and a digest of its source), so a
restored model is the model the same build makes (``tests/test_snapshot.py`` compares them
field by field). The per-pair entries are still written: slices and other scenes share them.
Builds of orientation slices (``model_scene(memo=...)``) neither write nor read snapshots:
their obstacles are modelled once for all slices already, and a snapshot per slice would
store that model once per slice (at 10^4 bodies x 36 slices it took the cache from 0.78 to
1.44 GB, and the one-process build from 178 s to 238 s in a run on a busier machine).
"""

from __future__ import annotations

import functools
import hashlib
import json
from pathlib import Path

import numpy as np

from ..cobstacle.margin import Margin
from ..geometry.exact import Grid
from ..mesh.closed import ClosedMesh
from ..mesh.convex import ConvexPolytope
from .cache import _POLYTOPE, FORMAT
from .classify import BodyModel, Enclosing, _classify, _snapped_model

__all__ = ["snapshot_key", "snapshot_arrays", "Snapshot"]

# Bump when what a snapshot holds, or how it is read, changes.
SNAPSHOT = 2

_RESTORED, _CLASSIFY, _DROPPED, _SOLID, _SNAPPED = 0, 1, 2, 3, 4


def snapshot_key(scene, grid: Grid | None, robot_hull: bool, conservative: bool,
                 sums: bool) -> str:
    """SHA-256 hex key of everything a scene's model and its C-obstacles depend on.

    The obstacles' and the robot's names, float64 vertices and triangles (bytes: a ``-0.0``
    where a ``0.0`` was only misses), the reference point, the bounds, the grid when one is
    imposed, ``robot_hull``, ``conservative`` and ``sums``, the cspace version, a digest of
    its source (:func:`_code`) and the cache format. Not the scene's name, start, goal or file names: they change no C-obstacle.
    """
    bodies = [scene.robot, *scene.obstacles]
    imposed = None if grid is None else [grid.exponent, grid.bits, list(grid.origin)]
    h = hashlib.sha256()
    h.update(json.dumps({"cspace": _code(), "format": FORMAT, "snapshot": SNAPSHOT,
                         "grid": imposed, "robot_hull": bool(robot_hull),
                         "conservative": bool(conservative), "sums": bool(sums),
                         "names": [b.name for b in bodies]}).encode())
    sizes = np.array([(len(b.vertices), len(b.faces)) for b in bodies], dtype=np.int64)
    for a in (sizes, np.concatenate([b.vertices for b in bodies]),
              np.concatenate([b.faces for b in bodies]),
              np.asarray(scene.reference_point, dtype=np.float64),
              np.asarray(scene.bounds, dtype=np.float64)):
        h.update(f"|{a.dtype.str} {a.shape}|".encode())
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


@functools.lru_cache(maxsize=1)
def _code() -> str:
    """The version and a digest of the package's source (``.py`` and ``.pyx``, once per
    process, a few milliseconds): a snapshot holds the outcome of all modelling and building
    rules, so any change of the code that made it, not only of the version, makes it miss."""
    from .._version import __version__

    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for p in sorted(root.rglob("*.py*")):
        if p.suffix in (".py", ".pyx") and "__pycache__" not in p.parts:
            h.update(f"{p.relative_to(root).as_posix()}\0".encode())
            h.update(p.read_bytes())
    return f"{__version__} {h.hexdigest()}"


def _restorable(b: BodyModel) -> bool:
    return b.kind == "convex" and not b._solid.excess and not b.changed


def _a_solid(b: BodyModel) -> bool:
    return b.kind == "solid" and isinstance(b._solid, ClosedMesh) and not b.changed


def _compact(a: np.ndarray) -> np.ndarray:
    """int32 when every value fits (grid integers of a 26-bit grid do), else int64."""
    small = not len(a) or (int(a.min()) >= -2**31 and int(a.max()) < 2**31)
    return a.astype(np.int32 if small else np.int64)


def _joined(parts: list, cols: int) -> np.ndarray:
    """``parts`` end to end (rows of ``cols`` columns; 0: a flat array), compacted."""
    if parts:
        return _compact(np.concatenate(parts))
    return _compact(np.zeros((0, cols) if cols else 0, dtype=np.int64))


def snapshot_arrays(bodies: list, sources: dict, grid: Grid, margin: Margin,
                    one_convex_part: bool) -> dict | None:
    """The snapshot of a finished build (``model_scene``'s bodies, in order), as the arrays
    a cache entry holds; None when there is nothing to keep (a failed build is not kept: its
    bodies are built again)."""
    if any(b.error for b in bodies):
        return None
    codes = np.array([_RESTORED if _restorable(b) else _SOLID if _a_solid(b)
                      else _SNAPPED if b._kept
                      else _CLASSIFY if len(b.faces) else _DROPPED
                      for b in bodies], dtype=np.int8)
    snapped = [b for b, c in zip(bodies, codes) if c == _SNAPPED]
    solids = [b._solid for b, c in zip(bodies, codes) if c == _SOLID]
    restored = [b for b, c in zip(bodies, codes) if c == _RESTORED]
    # the convex C-obstacles, when every restored body has its one (one convex robot part),
    # grown by the scene's margin (as a convex body's always is: it is not stored)
    with_cos = one_convex_part and all(b.co is not None and b.co.kind == "convex"
                                       and b.co.margin == margin for b in restored)
    shaped = [b for b, c in zip(bodies, codes) if c != _DROPPED]
    reasons: dict = {}
    meta = {
        "grid": [grid.exponent, grid.bits, list(grid.origin)],
        "margin": [list(margin.steps), [float(d) for d in margin.deviation],
                   float(margin.rounding), bool(margin.conservative)],
        "sources": sources,
        "bodies": [[b.name, b.source, reasons.setdefault(b.reason, len(reasons))]
                   for b in bodies],
        "reasons": list(reasons),
    }
    out = {
        "meta": np.frombuffer(json.dumps(meta).encode(), dtype=np.uint8),
        "codes": codes,
        "sheet": np.array([bool(b._sheet) for b in shaped], dtype=bool),
        "ints": _joined([b._ints for b in shaped], 3),
        "faces": _joined([b.faces for b in shaped], 3),
        "sizes": np.array([(len(b._ints), len(b.faces)) for b in shaped],
                          dtype=np.int64).reshape(-1, 2),
    }
    out |= _packed("poly", [b._solid for b in restored])
    out |= {"solid_ints": _joined([m.ints for m in solids], 3),
            "solid_faces": _joined([m.faces for m in solids], 3),
            "solid_components": _joined([m.components for m in solids], 0),
            "solid_sizes": np.array([(len(m.ints), len(m.faces)) for m in solids],
                                    dtype=np.int64).reshape(-1, 2)}
    # what snapping took (its segments and points are the shaped arrays): the enclosed
    # region's triangles, -1 where it has none
    out |= {"kept_faces": _joined([b._encloses.faces for b in snapped
                                   if b._encloses is not None], 3),
            "kept_sizes": np.array([-1 if b._encloses is None else len(b._encloses.faces)
                                    for b in snapped], dtype=np.int64)}
    if with_cos:
        out |= _packed("co", [b.co.polytope for b in restored])
    return out


def _packed(name: str, polytopes: list) -> dict:
    """Polytopes as one array per field (each field's rows of all of them, in order) and a
    table of each one's row counts: restoring one is then six slices, no reshaping."""
    out = {f"{name}_rows": np.array([[len(getattr(p, f)) for f, _ in _POLYTOPE]
                                     for p in polytopes], dtype=np.int64).reshape(-1, 6)}
    for f, cols in _POLYTOPE:
        out[f"{name}_{f}"] = _joined([getattr(p, f) for p in polytopes], cols)
    return out


def _polytopes(a: dict, name: str, grid: Grid, names: list) -> list:
    """The polytopes :func:`_packed` stored, as views of its arrays."""
    P, FO, FI, N, E, EF = (a[f"{name}_{f}"].astype(np.int64) for f, _ in _POLYTOPE)
    ends = np.cumsum(a[f"{name}_rows"], axis=0)
    starts = (ends - a[f"{name}_rows"]).tolist()
    # one polytope: six slices, written out (this loop runs once per body of a scene)
    return [ConvexPolytope(grid=grid, ints=P[p0:p1], facet_offsets=FO[o0:o1],
                           facet_indices=FI[i0:i1], normals=N[n0:n1], edges=E[e0:e1],
                           edge_facets=EF[f0:f1], name=label)
            for label, (p0, o0, i0, n0, e0, f0), (p1, o1, i1, n1, e1, f1)
            in zip(names, starts, ends.tolist())]


def _slices(sizes: np.ndarray) -> list:
    """Start offsets of consecutive runs of the given lengths (and the total last)."""
    return np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64).tolist()


class Snapshot:
    """A snapshot read back (:func:`Snapshot.read`): the grid and margin at once, the bodies
    by :meth:`bodies`."""

    def __init__(self, arrays: dict, meta: dict):
        self.arrays = arrays
        self.meta = meta
        e, bits, origin = meta["grid"]
        self.grid = Grid(int(e), int(bits), tuple(int(x) for x in origin))
        steps, deviation, rounding, conservative = meta["margin"]
        self.margin = Margin(tuple(int(s) for s in steps), tuple(float(d) for d in deviation),
                             self.grid, float(rounding), bool(conservative))
        self.sources = meta["sources"]

    @classmethod
    def read(cls, arrays: dict | None) -> "Snapshot | None":
        """The snapshot in a cache entry's arrays (None: no entry, or not one of ours)."""
        if arrays is None or "meta" not in arrays:
            return None
        try:
            snap = cls(arrays, json.loads(arrays["meta"].tobytes()))
        except (ValueError, KeyError, TypeError):
            return None
        return snap if snap._whole() else None

    def _whole(self) -> bool:
        """Every array there, of lengths that agree (a digest guards the bytes and the key
        the layout; this guards against a snapshot written by other code)."""
        a, bodies = self.arrays, self.meta.get("bodies")
        need = ("codes", "sheet", "ints", "faces", "sizes", "poly_rows",
                *(f"poly_{f}" for f, _ in _POLYTOPE), "solid_ints", "solid_faces",
                "solid_components", "solid_sizes", "kept_faces", "kept_sizes")
        if not isinstance(bodies, list) or any(k not in a for k in need):
            return False
        codes = a["codes"]
        shaped, restored = int((codes != _DROPPED).sum()), int((codes == _RESTORED).sum())
        sizes, solid = a["sizes"], a["solid_sizes"]
        return (len(codes) == len(bodies) and sizes.shape == (shaped, 2)
                and solid.shape == (int((codes == _SOLID).sum()), 2)
                and int(solid[:, 0].sum()) == len(a["solid_ints"])
                and int(solid[:, 1].sum()) == len(a["solid_faces"])
                == len(a["solid_components"])
                and len(a["sheet"]) == shaped
                and len(a["kept_sizes"]) == int((codes == _SNAPPED).sum())
                and int(a["kept_sizes"][a["kept_sizes"] > 0].sum()) == len(a["kept_faces"])
                and int(sizes[:, 0].sum()) == len(a["ints"])
                and int(sizes[:, 1].sum()) == len(a["faces"])
                and all(self._table(p, restored) for p in ("poly", "co")
                        if p == "poly" or "co_rows" in a))

    def _table(self, name: str, n: int) -> bool:
        """``n`` polytopes stored by :func:`_packed` under ``name``, every field whole."""
        a = self.arrays
        rows = a[f"{name}_rows"]
        if rows.shape != (n, 6):
            return False
        sums = rows.sum(axis=0).tolist()
        return all(f"{name}_{f}" in a and len(a[f"{name}_{f}"]) == k
                   for (f, _), k in zip(_POLYTOPE, sums))

    def bodies(self, minus_r_box, bounds_g, convex_robot: bool, robot_name: str = "",
               memo=None) -> tuple[list, dict]:
        """The modelled bodies, in order, and per restored body (by id) the arrays of its
        convex C-obstacle as a per-pair cache entry holds them, unpacked (empty without
        them); ``robot_name``: the convex robot part's, which names them."""
        a, grid = self.arrays, self.grid
        ints = a["ints"].astype(np.int64)
        faces = a["faces"].astype(np.int64)
        vertices = grid.to_float(ints) if len(ints) else np.zeros((0, 3))
        sizes = a["sizes"]
        v_at, f_at = _slices(sizes[:, 0]), _slices(sizes[:, 1])
        names = [b[0] for b, c in zip(self.meta["bodies"], a["codes"].tolist())
                 if c == _RESTORED]
        polys = _polytopes(a, "poly", grid, names)
        cos = (None if "co_rows" not in a else  # unpacked: _from_arrays takes them as they are
               [{"polytope": p} for p in _polytopes(a, "co", grid,
                                                    [f"{n}+-{robot_name}" for n in names])])
        sheet = a["sheet"].tolist()
        reasons = self.meta["reasons"]
        m_ints, m_faces = a["solid_ints"].astype(np.int64), a["solid_faces"].astype(np.int64)
        m_comp = a["solid_components"].astype(np.int64)
        mv_at, mf_at = _slices(a["solid_sizes"][:, 0]), _slices(a["solid_sizes"][:, 1])
        kept_faces = a["kept_faces"].astype(np.int64)
        kept_sizes = a["kept_sizes"].tolist()
        kf_at = _slices([max(n, 0) for n in kept_sizes])
        out, co_arrays = [], {}
        k = r = m = s = 0  # shaped body, restored body, solid, what snapping took
        for code, (name, source, why) in zip(a["codes"].tolist(), self.meta["bodies"]):
            if code == _DROPPED:
                out.append(BodyModel(name, source, "dropped", reasons[why], np.zeros((0, 3)),
                                     np.zeros((0, 3), dtype=np.int64)))
                continue
            P, F = ints[v_at[k]:v_at[k + 1]], faces[f_at[k]:f_at[k + 1]]
            if code == _SNAPPED:
                enclosing = (None if kept_sizes[s] < 0 else
                             Enclosing(P, kept_faces[kf_at[s]:kf_at[s + 1]]))
                out.append(_snapped_model(source, P, F, enclosing, reasons[why], minus_r_box,
                                          bounds_g, grid))
                s += 1
            elif code == _CLASSIFY:
                out.append(_classify(name, source, P, F, minus_r_box, bounds_g, grid,
                                     convex_robot, memo, sheet=sheet[k]))
            elif code == _SOLID:  # validated when the snapshot was written (its key: the code)
                f0, f1 = mf_at[m], mf_at[m + 1]
                mesh = ClosedMesh._trusted(m_ints[mv_at[m]:mv_at[m + 1]], m_faces[f0:f1],
                                           grid, name, m_comp[f0:f1])
                out.append(BodyModel(name, source, "solid", reasons[why],
                                     vertices[v_at[k]:v_at[k + 1]], F, _ints=P, _solid=mesh,
                                     _sheet=sheet[k]))
                m += 1
            else:
                body = BodyModel(name, source, "convex", reasons[why],
                                 vertices[v_at[k]:v_at[k + 1]], F, _ints=P, _solid=polys[r],
                                 _sheet=sheet[k])
                out.append(body)
                if cos is not None:
                    co_arrays[id(body)] = cos[r]
                r += 1
            k += 1
        return out, co_arrays
