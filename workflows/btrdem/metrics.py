"""Structural measures of a packing (DESIGN.md section 5).

Lengths are reported in mean diameters d (the mean of 2 r over all grains) unless named otherwise.
Whole-packing measures are taken in a bulk window: centres (or sample points) at least `floor`
diameters above the floor, `wall` diameters from the side walls (not the plates of a Hele-Shaw
cell, which every grain is near) and `surface` diameters below the local free surface. Periodic containers use the nearest periodic image everywhere.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from .geometry import Container


@dataclass(frozen=True)
class Window:
    floor: float = 2.0    # mean diameters above the floor
    wall: float = 2.0     # mean diameters from side walls
    surface: float = 2.0  # mean diameters below the local free surface
    cell: float = 2.0     # lateral cell of the free-surface height field, in mean diameters

    def as_dict(self):
        return asdict(self)


CONTACT_TOLERANCE = 0.01  # touching: centre distance < (r_i + r_j) (1 + tol)


def mean_diameter(radius: np.ndarray) -> float:
    return float(2.0 * np.mean(radius))


# ---- displacement ---------------------------------------------------------------------------------

def displacement(pre_pos: np.ndarray, post_pos: np.ndarray, container: Container) -> np.ndarray:
    """Displacement vectors (x, y, z), nearest periodic image for periodic containers."""
    return container.minimum_image_xyz(post_pos - pre_pos)


def local_displacement(pre_pos: np.ndarray, disp: np.ndarray, container: Container, reach: float) -> np.ndarray:
    """|u_i - mean of u_j over the grains j within `reach` of grain i (pre positions, i included)|:
    the part of a grain's displacement its neighbourhood did not share. A bed settling as a whole
    (elastic compression, a rigid shift) has large displacements but small local ones."""
    coords = container.coords(pre_pos)
    tree = _tree(coords, container)
    lists = tree.query_ball_point(container.wrap(coords), reach, return_sorted=False)
    out = np.empty(len(disp))
    for i, nb in enumerate(lists):
        out[i] = np.linalg.norm(disp[i] - disp[nb].mean(axis=0))
    return out


def displacement_stats(disp_d: np.ndarray, thresholds=(0.1, 0.5)) -> dict:
    """Per-grain displacement magnitudes in mean diameters -> summary."""
    if len(disp_d) == 0:
        raise ValueError("displacement statistics of an empty packing")
    out = {"mean": float(np.mean(disp_d)), "p95": float(np.percentile(disp_d, 95)), "max": float(np.max(disp_d)),
           "median": float(np.median(disp_d))}
    for t in thresholds:
        out[f"fraction_above_{t:g}"] = float(np.mean(disp_d > t))
    return out


# ---- free surface ---------------------------------------------------------------------------------

class SurfaceField:
    """Free-surface height on a lateral grid: the top (z + r) of the grains whose centre lies in each
    cell; 0 (the floor) for empty cells. `local_min` is the lowest surface over a cell and its
    neighbours, which keeps a bulk window below the surface where the surface is rough."""

    def __init__(self, coords: np.ndarray, r: np.ndarray, container: Container, cell: float):
        self.container = container
        self.nlat = coords.shape[1] - 1
        lo, hi = container.lateral_bounds(_xyz(coords, container), r)
        self.lo, self.hi = lo, hi
        span = np.maximum(hi - lo, 1e-300)
        self.n = np.maximum(1, np.floor(span / cell).astype(int))
        self.size = span / self.n
        h = np.zeros(tuple(self.n))
        if len(coords):
            idx = self.index(coords[:, :self.nlat])
            np.maximum.at(h, tuple(idx.T), coords[:, -1] + r)
        self.h = h
        periodic = container.periods()[:self.nlat] > 0
        mode = ["wrap" if p else "nearest" for p in periodic]
        self.h_min = ndimage.minimum_filter(h, size=3, mode=mode)

    def index(self, lat: np.ndarray) -> np.ndarray:
        lat = np.atleast_2d(lat)
        idx = np.floor((lat - self.lo) / self.size).astype(int)
        periodic = self.container.periods()[:self.nlat] > 0
        for k in range(self.nlat):
            if periodic[k]:
                idx[:, k] = np.mod(idx[:, k], self.n[k])
            else:
                idx[:, k] = np.clip(idx[:, k], 0, self.n[k] - 1)
        return idx

    def height(self, lat: np.ndarray) -> np.ndarray:
        return self.h[tuple(self.index(lat).T)]

    def local_min(self, lat: np.ndarray) -> np.ndarray:
        return self.h_min[tuple(self.index(lat).T)]

    def outside_footprint(self, lat: np.ndarray) -> np.ndarray:
        """Points beyond the grid (open containers): never bulk."""
        lat = np.atleast_2d(lat)
        return np.any((lat < self.lo) | (lat > self.hi), axis=1)


def _xyz(coords: np.ndarray, container: Container) -> np.ndarray:
    """coords() back to (x, y, z) (2D: y = 0)."""
    if container.dimension == 3:
        return coords
    out = np.zeros((len(coords), 3))
    out[:, 0], out[:, 2] = coords[:, 0], coords[:, 1]
    return out


class Bulk:
    """The bulk window of one packing: a membership test for any point, and its grains."""

    def __init__(self, pos: np.ndarray, r: np.ndarray, container: Container, window: Window, d: float):
        self.container, self.window, self.d = container, window, d
        self.coords = container.coords(pos)
        self.r = r
        self.surface = SurfaceField(self.coords, r, container, window.cell * d)

    def contains(self, q: np.ndarray) -> np.ndarray:
        """q in coords() form (N, D)."""
        nlat = q.shape[1] - 1
        z = q[:, -1]
        ok = z > self.window.floor * self.d
        ok &= self.container.wall_distance(_xyz(q, self.container), plates=False) > self.window.wall * self.d
        ok &= ~self.surface.outside_footprint(q[:, :nlat])
        ok &= z < self.surface.local_min(q[:, :nlat]) - self.window.surface * self.d
        return ok

    def grain_mask(self) -> np.ndarray:
        return self.contains(self.coords)

    def surface_distance(self) -> np.ndarray:
        """Distance of each centre below the free surface of its cell [m]."""
        nlat = self.coords.shape[1] - 1
        return self.surface.height(self.coords[:, :nlat]) - self.coords[:, -1]


# ---- neighbour search -----------------------------------------------------------------------------

def _tree(coords: np.ndarray, container: Container, extra: np.ndarray | None = None) -> cKDTree:
    data = container.wrap(coords)
    periods = container.periods()
    if extra is not None:
        data = np.column_stack([data, extra])
        periods = np.append(periods, 0.0)
    if np.any(periods > 0):
        return cKDTree(data, boxsize=periods)
    return cKDTree(data)


def _query_points(q: np.ndarray, container: Container, extra_zero: bool = False) -> np.ndarray:
    q = container.wrap(q)
    return np.column_stack([q, np.zeros(len(q))]) if extra_zero else q


def contact_pairs(pos: np.ndarray, r: np.ndarray, container: Container, tol: float = CONTACT_TOLERANCE):
    """Pairs (i, j), i < j, with centre distance < (r_i + r_j)(1 + tol), and those distances."""
    coords = container.coords(pos)
    if len(coords) < 2:
        return np.zeros((0, 2), dtype=int), np.zeros(0)
    tree = _tree(coords, container)
    r_max = float(np.max(r))
    if r_max / float(np.min(r)) < 3.0:
        pairs = tree.query_pairs(2.0 * r_max * (1.0 + tol), output_type="ndarray")
    else:  # wide size distributions: search each grain's own reach, not the largest one
        lists = tree.query_ball_point(container.wrap(coords), (r + r_max) * (1.0 + tol), return_sorted=False)
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


def contact_numbers(n: int, pairs: np.ndarray) -> np.ndarray:
    z = np.zeros(n, dtype=int)
    np.add.at(z, pairs[:, 0], 1)
    np.add.at(z, pairs[:, 1], 1)
    return z


# ---- packing fraction -----------------------------------------------------------------------------

def packing_fraction(bulk: Bulk, spacing: float | None = None, max_points: int = 2_000_000, seed: int = 12345):
    """Solid fraction of the bulk window by stratified sampling: one point, uniformly placed, in each
    cell of a regular grid (cell `spacing`, default d/8, coarsened to stay under max_points).
    Returns (fraction, window volume [m^3 or m^2 in 2D], number of sample points in the window)."""
    c, r, cont, d = bulk.coords, bulk.r, bulk.container, bulk.d
    dim = c.shape[1]
    nlat = dim - 1
    lo = np.append(bulk.surface.lo, bulk.window.floor * d)
    top = float(np.max(bulk.surface.h)) - bulk.window.surface * d
    hi = np.append(bulk.surface.hi, top)
    if top <= lo[-1]:
        return None, 0.0, 0
    span = hi - lo
    h = spacing or d / 8.0
    while np.prod(np.ceil(span / h)) > max_points:
        h *= 1.25
    n = np.ceil(span / h).astype(int)
    step = span / n
    rng = np.random.default_rng(seed)
    # A lifted 4D (3D for disks) tree: point q is inside sphere i iff |q - c_i|^2 - r_i^2 < 0, i.e.
    # iff its distance to (c_i, sqrt(R^2 - r_i^2)) is below R, so one nearest-neighbour query
    # answers "inside any grain" for any size distribution.
    big = float(np.max(r))
    tree = _tree(c, cont, extra=np.sqrt(np.maximum(big * big - r * r, 0.0)))
    inside = 0
    total = 0
    # Slabs along the height keep memory bounded.
    per_layer = int(np.prod(n[:nlat]))
    layers_per_chunk = max(1, 400_000 // max(per_layer, 1))
    lat_axes = [lo[k] + step[k] * (np.arange(n[k]) + 0.5) for k in range(nlat)]
    lat = np.stack(np.meshgrid(*lat_axes, indexing="ij"), axis=-1).reshape(-1, nlat)
    for z0 in range(0, n[-1], layers_per_chunk):
        zs = lo[-1] + step[-1] * (np.arange(z0, min(n[-1], z0 + layers_per_chunk)) + 0.5)
        q = np.column_stack([np.tile(lat, (len(zs), 1)), np.repeat(zs, len(lat))])
        q += (rng.random(q.shape) - 0.5) * step
        q = q[bulk.contains(q)]
        if len(q) == 0:
            continue
        dist, _ = tree.query(_query_points(q, cont, extra_zero=True), k=1)
        inside += int(np.count_nonzero(dist < big))
        total += len(q)
    if total == 0:
        return None, 0.0, 0
    return inside / total, total * float(np.prod(step)), total


# ---- radial distribution function -----------------------------------------------------------------

def rdf(bulk: Bulk, mask: np.ndarray, volume: float, r_max_d: float = 3.0, bin_d: float = 0.02):
    """g(r) with the bulk grains as centres and every grain as neighbour, normalised by the bulk number
    density. Returns (r / d at bin centres, g). Shells reaching past the packing's edges are not
    corrected for; keep r_max near the window margins."""
    c, cont, d = bulk.coords, bulk.container, bulk.d
    edges = np.arange(0.0, r_max_d + 0.5 * bin_d, bin_d) * d
    centres = 0.5 * (edges[1:] + edges[:-1]) / d
    nb = int(mask.sum())
    if nb == 0 or volume <= 0:
        return centres, None
    tree = _tree(c, cont)
    lists = tree.query_ball_point(cont.wrap(c[mask]), edges[-1], return_sorted=False)
    src = np.repeat(np.nonzero(mask)[0], [len(x) for x in lists])
    dst = np.concatenate([np.asarray(x, dtype=int) for x in lists])
    keep = dst != src
    dist = np.linalg.norm(cont.minimum_image(c[dst[keep]] - c[src[keep]]), axis=1)
    counts, _ = np.histogram(dist, bins=edges)
    density = nb / volume
    if c.shape[1] == 3:
        shell = 4.0 / 3.0 * np.pi * (edges[1:] ** 3 - edges[:-1] ** 3)
    else:
        shell = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    return centres, counts / (nb * density * shell)


def rdf_distance(g1, g2, r_d, r_min_d: float = 0.5, coarsen: int = 5) -> float | None:
    """RMS difference of two g(r) on the same bins, over r >= r_min_d, after merging `coarsen`
    neighbouring bins (0.1 d with the default 0.02 d bins: the fine bins of a small packing are noise)."""
    if g1 is None or g2 is None:
        return None
    sel = np.asarray(r_d) >= r_min_d
    a, b = np.asarray(g1)[sel], np.asarray(g2)[sel]
    n = (len(a) // coarsen) * coarsen
    if n == 0:
        return None
    a, b = a[:n].reshape(-1, coarsen).mean(axis=1), b[:n].reshape(-1, coarsen).mean(axis=1)
    return float(np.sqrt(np.mean((a - b) ** 2)))


# ---- free-surface profile and angle of repose ----------------------------------------------------

def surface_profile(pos: np.ndarray, r: np.ndarray, container: Container, d: float, heap_axis=None,
                    bin_d: float = 1.0):
    """Top of the packing against a lateral coordinate: the distance from the heap axis (a point
    (x, y); 2D and Hele-Shaw cells use |x - x0|) when heap_axis is given, else x.
    Returns (coordinate [m] at bin centres, height [m]); bins holding no grain are dropped."""
    if len(pos) == 0:
        return np.zeros(0), np.zeros(0)
    top = pos[:, 2] + r
    if heap_axis is not None:
        x0, y0 = heap_axis
        if container.dimension == 2 or container.kind == "hele-shaw":
            s = np.abs(pos[:, 0] - x0)
        else:
            s = np.hypot(pos[:, 0] - x0, pos[:, 1] - y0)
        lo = 0.0
    else:
        s = pos[:, 0]
        lo = float(np.min(s))
    w = bin_d * d
    idx = np.floor((s - lo) / w).astype(int)
    nbin = int(idx.max()) + 1
    h = np.full(nbin, -np.inf)
    np.maximum.at(h, idx, top)
    ok = np.isfinite(h)
    coord = lo + w * (np.arange(nbin) + 0.5)
    return coord[ok], h[ok]


def angle_of_repose(coord: np.ndarray, height: np.ndarray, lo_frac: float = 0.15, hi_frac: float = 0.85):
    """Least-squares line through the flank of a heap profile (height against distance from the axis):
    the bins whose height lies between lo_frac and hi_frac of the top height, which leaves out the
    rounded apex and the foot. Returns a dict (angle in degrees) or None if too few bins."""
    if len(height) < 3:
        return None
    top = float(np.max(height))
    sel = (height > lo_frac * top) & (height < hi_frac * top)
    if np.count_nonzero(sel) < 3:
        return None
    slope, intercept = np.polyfit(coord[sel], height[sel], 1)
    resid = height[sel] - (slope * coord[sel] + intercept)
    return {"angle_deg": float(np.degrees(np.arctan(-slope))), "slope": float(slope),
            "intercept": float(intercept), "n_points": int(np.count_nonzero(sel)),
            "rms_residual": float(np.sqrt(np.mean(resid ** 2))),
            "fit_range": [float(coord[sel].min()), float(coord[sel].max())]}


# ---- segregation ----------------------------------------------------------------------------------

def segregation_index(pos: np.ndarray, r: np.ndarray, species: np.ndarray):
    """Vertical size segregation S = 2 (zL - zS) / (zL + zS) from the mean centre heights of the large
    and small grains: > 0 when the large grains ride on top (Brazil-nut), 0 when mixed.
    Mixtures (2 or more species) split by species (the largest and the smallest by mean radius);
    a single polydisperse species splits at the median radius; None for one size."""
    z = pos[:, 2]
    kinds = np.unique(species)
    if len(kinds) >= 2:
        mean_r = {int(k): float(np.mean(r[species == k])) for k in kinds}
        small = min(mean_r, key=mean_r.get)
        large = max(mean_r, key=mean_r.get)
        if mean_r[small] == mean_r[large]:
            return None
        zs, zl = z[species == small], z[species == large]
        basis = f"species {large} (large) vs {small} (small)"
    else:
        if np.max(r) <= np.min(r) * 1.05:
            return None
        med = np.median(r)
        zs, zl = z[r <= med], z[r > med]
        if len(zl) == 0 or len(zs) == 0:
            return None
        basis = "radius above vs below the median"
    mzs, mzl = float(np.mean(zs)), float(np.mean(zl))
    return {"index": 2.0 * (mzl - mzs) / (mzl + mzs), "mean_height_large": mzl, "mean_height_small": mzs,
            "basis": basis}


# ---- everything at once ---------------------------------------------------------------------------

def heap_axis_of(scene: dict | None):
    """The heap axis (x, y) for a point source, else None."""
    if not scene:
        return None
    src = scene.get("source") or {}
    if src.get("kind") != "point":
        return None
    if "position" in src:
        p = list(src["position"]) + [0.0]
        return float(p[0]), float(p[1]) if len(src["position"]) > 1 else 0.0
    return float(src.get("x", 0.0)), float(src.get("y", 0.0))


def structure(pos: np.ndarray, r: np.ndarray, species: np.ndarray, container: Container, d: float | None = None,
              window: Window = Window(), heap_axis=None, tol: float = CONTACT_TOLERANCE,
              rdf_max_d: float = 3.0, rdf_bin_d: float = 0.02) -> dict:
    """All structural measures of one packing, JSON-ready (arrays as lists)."""
    d = d or mean_diameter(r)
    bulk = Bulk(pos, r, container, window, d)
    mask = bulk.grain_mask()
    phi, volume, npts = packing_fraction(bulk)
    pairs, _ = contact_pairs(pos, r, container, tol)
    z = contact_numbers(len(r), pairs)
    zb = z[mask]
    dist = None
    if len(zb):
        counts = np.bincount(zb)
        dist = {str(k): float(c / len(zb)) for k, c in enumerate(counts)}
    r_d, g = rdf(bulk, mask, volume, rdf_max_d, rdf_bin_d)
    coord, height = surface_profile(pos, r, container, d, heap_axis)
    aor = angle_of_repose(coord, height) if heap_axis is not None else None
    return {
        "n_grains": int(len(r)),
        "mean_diameter": d,
        "window": dict(window.as_dict(), contact_tolerance=tol, n_bulk_grains=int(mask.sum()),
                       volume=volume, sample_points=npts),
        "packing_fraction": phi,
        "coordination": {"mean": float(np.mean(zb)) if len(zb) else None,
                         "mean_all_grains": float(np.mean(z)) if len(z) else None,
                         "distribution": dist},
        "rdf": {"r_over_d": r_d.tolist(), "g": None if g is None else g.tolist()},
        "surface_profile": {"mode": "radial" if heap_axis is not None else "x",
                            "coord": coord.tolist(), "height": height.tolist()},
        "angle_of_repose": aor,
        "segregation": segregation_index(pos, r, species),
        "height": {"max_top": float(np.max(pos[:, 2] + r)) if len(r) else None,
                   "mean_centre": float(np.mean(pos[:, 2])) if len(r) else None},
    }
