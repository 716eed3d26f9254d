"""Exact endpoints of triangle-pair intersection segments (NCC-CVMS steps 4–5).

:func:`endpoint_coordinates` turns the symbolic endpoints that :func:`cspace.geometry.tritri.intersect_pairs`
reports (a vertex, or an edge crossing a plane) into exact homogeneous integer points; compiled,
with its pure-Python reference :func:`_endpoint_coordinates_reference`.
"""

from __future__ import annotations

from math import gcd

import numpy as np

from ._kernels import load
from .tritri import EDGE_PLANE, TriTriResult, VERTEX, _check_soup, _object_array

__all__ = ["ENDPOINT_KINDS", "endpoint_coordinates"]


# The box sweep, the pair classification and the endpoint coordinates run compiled
# (cspace.geometry._kernels.arrangement); their numpy references are BoxSweep._pairs_reference,
# _intersect_pairs_reference and _endpoint_coordinates_reference, which they match exactly.
_compiled = load("arrangement")


#: Names of the endpoint kinds, indexed by ``TriTriResult.kind``.
ENDPOINT_KINDS = ("none", "vertex", "edge_plane")


# --------------------------------------------------------------------------------------
# coordinates of symbolic points


def endpoint_coordinates(ints, faces, result: TriTriResult):
    """Exact homogeneous coordinates and float approximations of the symbolic endpoints.

    Parameters
    ----------
    ints : (n, 3) int64
        Vertex positions in grid units (as passed to :func:`~cspace.geometry.tritri.intersect_pairs`).
    faces : (t, 3) int64
        The triangles (as passed to :func:`~cspace.geometry.tritri.intersect_pairs`).
    result : TriTriResult

    Returns
    -------
    exact : (k, 2) object
        For each endpoint, the tuple ``(X, Y, Z, W)`` of Python ints with ``W > 0`` and
        ``gcd(X, Y, Z, W) == 1``: the point is ``(X, Y, Z) / W`` in grid units. Equal points
        give equal tuples. None where a pair has no endpoint.
    approx : (k, 2, 3) float64
        ``(X, Y, Z) / W`` correctly rounded; NaN where there is no endpoint.

    Notes
    -----
    An edge ``(u, v)`` crossing the plane of triangle ``t`` with ``s_x = N_t · (x - t_0)``
    is the point ``(s_u v - s_v u) / (s_u - s_v)``. Compiled
    (:func:`cspace.geometry._kernels.arrangement.endpoint_coordinates`, in 128-bit integers); the
    reference is :func:`_endpoint_coordinates_reference`.
    """
    ints, faces = _check_soup(ints, faces)
    c = np.ascontiguousarray
    kind, u, v, plane = (c(result.kind, dtype=np.int8), c(result.u, dtype=np.int64),
                         c(result.v, dtype=np.int64), c(result.plane, dtype=np.int64))
    # The kernel trusts its indices: check them as the reference's numpy indexing would.
    isv, ise = kind == VERTEX, kind == EDGE_PLANE
    for idx, sel, n in ((u, isv | ise, len(ints)), (v, ise, len(ints)), (plane, ise, len(faces))):
        if sel.any() and not (0 <= idx[sel].min() and idx[sel].max() < n):
            raise IndexError(f"an endpoint refers to an index outside [0, {n})")
    return _compiled.endpoint_coordinates(c(ints), c(faces), kind, u, v, plane)


def _endpoint_coordinates_reference(ints, faces, result: TriTriResult):
    """:func:`endpoint_coordinates` in numpy and Python integers (the reference of the
    compiled kernel: equal tuples, bit-identical floats)."""
    ints, faces = _check_soup(ints, faces)
    k = len(result)
    ex = np.full((k, 2), None, dtype=object)
    approx = np.full((k, 2, 3), np.nan)
    kind = np.asarray(result.kind)
    isv = kind == VERTEX
    if isv.any():
        labels = np.asarray(result.u)[isv]
        uniq, inv = np.unique(labels, return_inverse=True)
        ex[isv] = _object_array([(x, y, z, 1) for x, y, z in ints[uniq].tolist()])[inv.reshape(-1)]
        approx[isv] = ints[labels].astype(np.float64)
    ise = kind == EDGE_PLANE
    if ise.any():
        keys = np.stack([np.asarray(result.u)[ise], np.asarray(result.v)[ise], np.asarray(result.plane)[ise]], axis=1)
        uniq, inv = np.unique(keys, axis=0, return_inverse=True)
        corners = ints[faces[uniq[:, 2]]].tolist()
        points = [
            _edge_plane_point(pu, pv, tri)
            for pu, pv, tri in zip(ints[uniq[:, 0]].tolist(), ints[uniq[:, 1]].tolist(), corners)
        ]
        ex[ise] = _object_array([p[0] for p in points])[inv.reshape(-1)]
        approx[ise] = np.array([p[1] for p in points], dtype=np.float64).reshape(-1, 3)[inv.reshape(-1)]
    return ex, approx


def _edge_plane_point(pu, pv, tri):
    """Canonical ``(X, Y, Z, W)`` and floats of the edge ``pu pv`` crossing the plane of ``tri``.

    All arguments are Python-int coordinate lists; the edge must cross the plane. (Written
    out in scalars: it runs once per distinct crossing, in Python.)
    """
    (ax, ay, az), (bx, by, bz), (cx, cy, cz) = tri
    ux, uy, uz = bx - ax, by - ay, bz - az
    vx, vy, vz = cx - ax, cy - ay, cz - az
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    su = nx * (pu[0] - ax) + ny * (pu[1] - ay) + nz * (pu[2] - az)
    sv = nx * (pv[0] - ax) + ny * (pv[1] - ay) + nz * (pv[2] - az)
    W = su - sv
    if W == 0:
        raise ValueError(f"the edge {pu} {pv} does not cross the plane of {tri}")
    X, Y, Z = su * pv[0] - sv * pu[0], su * pv[1] - sv * pu[1], su * pv[2] - sv * pu[2]
    if W < 0:
        X, Y, Z, W = -X, -Y, -Z, -W
    g = gcd(X, Y, Z, W)
    if g != 1:
        X, Y, Z, W = X // g, Y // g, Z // g, W // g
    # Python's int / int is correctly rounded.
    return (X, Y, Z, W), (X / W, Y / W, Z / W)
