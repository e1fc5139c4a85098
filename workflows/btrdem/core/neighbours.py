"""Neighbour search on packings (periodic sides wrap, through geometry.Container): the points within a
distance and the touching pairs, for the support analysis and the local displacement of the workflows.
The coordination number is not computed here: it is a measure, and `btr measure`
(btr/measures/metrics.cpp) is its one definition."""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .geometry import Container


def _tree(coords: np.ndarray, container: Container) -> cKDTree:
    """A k-d tree of coords() positions, periodic where the container is."""
    data = container.wrap(coords)
    periods = container.periods()
    if np.any(periods > 0):
        return cKDTree(data, boxsize=periods)
    return cKDTree(data)


def within(coords: np.ndarray, container: Container, reach) -> list:
    """For each point of coords(), the indices of the points within `reach` of it (a number, or one per
    point), itself included, in no particular order."""
    return _tree(coords, container).query_ball_point(container.wrap(coords), reach, return_sorted=False)


def touching_pairs(pos: np.ndarray, r: np.ndarray, container: Container, tol: float = 0.0):
    """Pairs (i, j), i < j, with centre distance < (r_i + r_j)(1 + tol), and those distances."""
    coords = container.coords(pos)
    if len(coords) < 2:
        return np.zeros((0, 2), dtype=int), np.zeros(0)
    r_max = float(np.max(r))
    if r_max / float(np.min(r)) < 3.0:
        pairs = _tree(coords, container).query_pairs(2.0 * r_max * (1.0 + tol), output_type="ndarray")
    else:  # wide size distributions: search each grain's own reach, not the largest one
        lists = within(coords, container, (r + r_max) * (1.0 + tol))
        ii = np.repeat(np.arange(len(lists)), [len(x) for x in lists])
        jj = np.concatenate([np.asarray(x, dtype=int) for x in lists]) if len(lists) else np.zeros(0, int)
        keep = jj > ii
        pairs = np.column_stack([ii[keep], jj[keep]])
    if len(pairs) == 0:
        return np.zeros((0, 2), dtype=int), np.zeros(0)
    delta = container.minimum_image(coords[pairs[:, 1]] - coords[pairs[:, 0]])
    dist = np.linalg.norm(delta, axis=1)
    keep = dist < (r[pairs[:, 0]] + r[pairs[:, 1]]) * (1.0 + tol)
    return pairs[keep], dist[keep]
