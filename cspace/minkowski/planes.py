"""NCC-CVMS trimming, stage ``planes``: superset triangles grouped by exact supporting plane.

Each plane is keyed by its primitive integer normal and offset (exact), so coplanar triangles
of the superset, whatever their orientation, share one arrangement (:mod:`.arrangements`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .superset import Superset


@dataclass
class _Planes:
    """Superset triangles grouped by exact supporting plane.

    ``keys[p] = (n0, n1, n2, d)``: primitive normal with its first non-zero component positive
    and offset ``d = n · x`` (Python ints, grid units). ``sign[t]`` is +1 when triangle ``t``
    turns counter-clockwise around ``n`` (its normal is a positive multiple of ``n``).
    ``axis[p]`` is the coordinate dropped to project plane ``p`` (largest ``|n_i|``) and
    ``sigma[p] = sign(n[axis])``: counter-clockwise in the projection is the orientation of
    ``sigma * n``.
    """

    ints: np.ndarray
    faces: np.ndarray
    facet: np.ndarray
    weight: np.ndarray
    plane: np.ndarray
    sign: np.ndarray
    keys: list
    axis: np.ndarray
    sigma: np.ndarray
    members: list  # triangles of each plane

    def normal(self, p: int) -> tuple[int, int, int]:
        """``sigma * n``: the orientation counter-clockwise projected faces have."""
        s = int(self.sigma[p])
        n = self.keys[p]
        return (s * n[0], s * n[1], s * n[2])


def _plane_groups(S: Superset) -> _Planes:
    faces, facet, weight = S.triangles()
    P = S.ints[faces]
    N = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])  # |k| < 2**29: below 2**61
    keep = (weight > 0) & np.any(N != 0, axis=1)
    faces, facet, weight, N, P = faces[keep], facet[keep], weight[keep], N[keep], P[keep]
    g = np.gcd.reduce(np.abs(N), axis=1)
    n = N // g[:, None]
    first = np.where(n[:, 0] != 0, n[:, 0], np.where(n[:, 1] != 0, n[:, 1], n[:, 2]))
    sign = np.sign(first).astype(np.int8)
    n = n * sign[:, None]
    no, ao = n.astype(object), P[:, 0].astype(object)
    d = no[:, 0] * ao[:, 0] + no[:, 1] * ao[:, 1] + no[:, 2] * ao[:, 2]
    index: dict = {}
    plane = np.empty(len(faces), dtype=np.int64)
    for k, key in enumerate(zip(n[:, 0].tolist(), n[:, 1].tolist(), n[:, 2].tolist(), d.tolist())):
        plane[k] = index.setdefault(key, len(index))
    keys = list(index)
    kn = np.array([k[:3] for k in keys], dtype=np.int64).reshape(-1, 3)
    axis = np.argmax(np.abs(kn), axis=1)
    sigma = np.sign(kn[np.arange(len(kn)), axis]).astype(np.int8)
    order = np.argsort(plane, kind="stable")
    bounds = np.searchsorted(plane[order], np.arange(len(keys) + 1))
    members = [order[bounds[p]: bounds[p + 1]] for p in range(len(keys))]
    return _Planes(S.ints, faces, facet, weight, plane, sign, keys, axis, sigma, members)
