"""What held each grain in a BTR packing: its supports when it was placed.

BTR places grains in id order and never moves them again, so grain i's supports are the grains
with a smaller id that touch it, the floor and the side walls. The stability of the placement is
read from the horizontal projection of the centre against the support polygon (the convex hull of
the projected contact points; a segment for two supports, an interval along x in 2D): its signed
distance to the polygon's edge, in units of the grain's radius (> 0 inside). A grain resting with
its centre just inside the edge is the kind of configuration DEM may reject (Schwager & Poeschel,
Fig. 14)."""
from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from ..core.geometry import Container
from ..core.neighbours import touching_pairs

SUPPORT_TOLERANCE = 1e-5  # BTR contacts touch exactly; relative gap accepted as touching


def _segment_margins(p: np.ndarray):
    """2D points (k, 2), collinear or two: the extreme pair as a segment. Returns (margin, offset):
    distance of the origin's projection on the segment's line from the nearer end (> 0 between the
    ends) and the origin's distance from that line."""
    centre = p.mean(axis=0)
    u, s, vt = np.linalg.svd(p - centre)
    direction = vt[0]
    t = (p - centre) @ direction
    a, b = centre + t.min() * direction, centre + t.max() * direction
    length = np.linalg.norm(b - a)
    if length == 0:
        return -float(np.linalg.norm(a)), float(np.linalg.norm(a))
    e = (b - a) / length
    along = float(-a @ e)
    offset = float(abs(-a[0] * e[1] + a[1] * e[0]))
    return min(along, length - along), offset


def polygon_margin(points_xy: np.ndarray, tol: float = 1e-9):
    """Signed distance of the origin to the support polygon spanned by points_xy (k, 2): > 0 inside.
    Returns (margin, offset, degenerate) where offset is the distance from the segment line for a
    degenerate (collinear) support, 0 otherwise."""
    k = len(points_xy)
    if k == 1:
        dist = float(np.linalg.norm(points_xy[0]))
        return -dist, dist, True
    if k >= 3:
        scale = float(np.max(np.abs(points_xy))) or 1.0
        try:
            hull = ConvexHull(points_xy / scale)
            if hull.volume > tol:
                # equations: outward normal n and offset o with n.x + o <= 0 inside
                return float(-np.max(hull.equations[:, 2]) * scale), 0.0, False
        except QhullError:
            pass
    margin, offset = _segment_margins(points_xy)
    return margin, offset, True


def btr_supports(pos: np.ndarray, r: np.ndarray, container: Container, tol: float = SUPPORT_TOLERANCE) -> dict:
    """Per-grain support analysis (arrays in id order). Keys:
      n_supports   earlier grains + floor + side walls touching
      n_grain_supports, floor (bool), walls (number of wall contacts)
      kind         'floor', '0', '1', '2', '3', '4+' (number of non-floor supports)
      edge_distance  signed distance of the centre's projection to the support polygon's edge / r
                     (NaN on the floor; 2D: the interval between the two contact points along x)
      offset       distance of the projection from the line of a two-point support / r
      load         number of later grains resting on the grain (touching, centre higher)
    """
    n = len(r)
    dim = container.dimension
    pairs, _ = touching_pairs(pos, r, container, tol)
    neighbours = [[] for _ in range(n)]
    for i, j in pairs:
        neighbours[max(i, j)].append(min(i, j))  # the later grain rests on the earlier one
    load = np.zeros(n, dtype=int)
    for i, j in pairs:
        lo, hi = min(i, j), max(i, j)
        if pos[hi, 2] > pos[lo, 2]:
            load[lo] += 1
    walls = container.wall_contacts(pos, r, tol)
    floor = pos[:, 2] - r <= tol * r

    n_grain = np.array([len(x) for x in neighbours], dtype=int)
    n_walls = np.array([len(x) for x in walls], dtype=int)
    edge = np.full(n, np.nan)
    offset = np.zeros(n)
    kind = np.empty(n, dtype=object)
    for i in range(n):
        k = n_grain[i] + n_walls[i]
        if floor[i]:
            kind[i] = "floor"
            continue
        kind[i] = str(k) if k < 4 else "4+"
        if k == 0:
            continue
        points = []
        for j in neighbours[i]:
            delta = container.minimum_image_xyz(pos[j] - pos[i])
            points.append(r[i] * delta / np.linalg.norm(delta))
        for q in walls[i]:
            points.append(q - pos[i])
        p = np.array(points)
        if dim == 2:
            xs = p[:, 0]
            lo, hi = xs.min(), xs.max()
            if k == 1 or hi - lo <= 0:
                edge[i] = -abs(float(xs[0])) / r[i]
            else:
                edge[i] = min(-lo, hi) / r[i]
            continue
        m, off, _ = polygon_margin(p[:, :2])
        edge[i], offset[i] = m / r[i], off / r[i]
    return {"n_supports": n_grain + n_walls + floor.astype(int), "n_grain_supports": n_grain, "floor": floor,
            "walls": n_walls, "kind": kind, "edge_distance": edge, "offset": offset, "load": load}


KIND_ORDER = ["floor", "0", "1", "2", "3", "4+"]
KIND_LABEL = {"floor": "on the floor", "0": "no support (floating)", "1": "1 support", "2": "2 supports (segment)",
              "3": "3 supports (triangle)", "4+": "4 or more supports"}
