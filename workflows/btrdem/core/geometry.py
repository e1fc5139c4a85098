"""The container a packing lives in, as every metric sees it (docs/design.md section 1, btr/model/container.h).

Floor z = 0; lateral geometry centred on the z axis:
  open       floor only
  box        walls at x = +-size_x/2 (and y = +-size_y/2 in 3D)
  periodic   periodic in x (and y in 3D), domain [-L/2, L/2)
  hele-shaw  (3D) plates y = +-gap/2, end walls x = +-size_x/2
  cylinder   (3D) wall at sqrt(x^2 + y^2) = radius
2D packings are disks in the x-z plane (y = 0).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

KINDS = ("open", "box", "periodic", "hele-shaw", "cylinder")


@dataclass(frozen=True)
class Container:
    kind: str = "open"
    dimension: int = 3
    size_x: float = 0.0
    size_y: float = 0.0
    gap: float = 0.0
    radius: float = 0.0

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"container kind: expected one of {', '.join(KINDS)}, got {self.kind!r}")
        if self.dimension not in (2, 3):
            raise ValueError(f"dimension: expected 2 or 3, got {self.dimension!r}")
        if self.dimension == 2 and self.kind in ("hele-shaw", "cylinder"):
            raise ValueError(f"container kind {self.kind!r} is 3D only")

    @staticmethod
    def from_json(container: dict, dimension: int, origin: str = "packing JSON") -> "Container":
        """From the "container" object of a scene JSON (coupling/io/scene_json.cpp) or a TOML [container]."""
        try:
            kind = container["kind"]
        except (KeyError, TypeError):
            raise ValueError(f"{origin}: container: expected an object with a 'kind'") from None
        size = container.get("size")
        size_x = float(container.get("size_x", size[0] if size else 0.0))
        size_y = float(container.get("size_y", size[1] if size and len(size) > 1 else 0.0))
        try:
            return Container(kind=kind, dimension=int(dimension), size_x=size_x, size_y=size_y,
                             gap=float(container.get("gap", 0.0)), radius=float(container.get("radius", 0.0)))
        except ValueError as e:
            raise ValueError(f"{origin}: {e}") from None

    # ---- coordinates: 3D uses (x, y, z); 2D uses (x, z) -------------------------------------------

    def coords(self, pos: np.ndarray) -> np.ndarray:
        """The coordinates the neighbour search works in: (x, y, z) in 3D, (x, z) in 2D (last column is height)."""
        return pos if self.dimension == 3 else pos[:, [0, 2]]

    def periods(self) -> np.ndarray:
        """Period of each coordinate of coords(); 0 where not periodic."""
        lx, ly, _ = self.periods_xyz()
        return np.array([lx, 0.0]) if self.dimension == 2 else np.array([lx, ly, 0.0])

    def periods_xyz(self) -> np.ndarray:
        """Period along x, y and z; 0 where not periodic."""
        periodic = self.kind == "periodic"
        return np.array([self.size_x if periodic else 0.0,
                         self.size_y if periodic and self.dimension == 3 else 0.0, 0.0])

    def wrap(self, c: np.ndarray) -> np.ndarray:
        """Coordinates shifted into [0, L) along periodic axes (what scipy's periodic cKDTree wants)."""
        c = np.array(c, dtype=float, copy=True)
        for k, length in enumerate(self.periods()):
            if length > 0:
                c[:, k] = np.mod(c[:, k] + 0.5 * length, length)
                c[c[:, k] >= length, k] = 0.0  # mod can round up to L
        return c

    def minimum_image(self, delta: np.ndarray) -> np.ndarray:
        """Difference vectors (in coords()) reduced to the nearest periodic image."""
        return _nearest_image(delta, self.periods())

    def minimum_image_xyz(self, delta: np.ndarray) -> np.ndarray:
        """Like minimum_image, for full (x, y, z) vectors."""
        return _nearest_image(delta, self.periods_xyz())

    # ---- walls ----------------------------------------------------------------------------------

    def has_walls(self) -> bool:
        return self.kind in ("box", "hele-shaw", "cylinder")

    def wall_distance(self, pos: np.ndarray, plates: bool = True) -> np.ndarray:
        """Distance from each point (x, y, z) to the nearest side wall; inf where there is none.
        plates=False leaves out the two plates of a Hele-Shaw cell (a quasi-2D cell is all near them)."""
        pos = np.atleast_2d(pos)
        x, y = pos[:, 0], pos[:, 1]
        inf = np.full(len(pos), np.inf)
        if self.kind == "box":
            d = 0.5 * self.size_x - np.abs(x)
            if self.dimension == 3:
                d = np.minimum(d, 0.5 * self.size_y - np.abs(y))
            return d
        if self.kind == "hele-shaw":
            ends = 0.5 * self.size_x - np.abs(x)
            return np.minimum(ends, 0.5 * self.gap - np.abs(y)) if plates else ends
        if self.kind == "cylinder":
            return self.radius - np.hypot(x, y)
        return inf

    def wall_contacts(self, pos: np.ndarray, r: np.ndarray, tol: float):
        """For each grain, the contact points (x, y, z) with side walls it touches within tol * r.

        Returns a list (one entry per grain) of lists of contact points."""
        out = [[] for _ in range(len(pos))]
        if not self.has_walls():
            return out
        planes = []
        if self.kind in ("box", "hele-shaw"):
            planes += [(0, 0.5 * self.size_x), (0, -0.5 * self.size_x)]
            if self.kind == "box" and self.dimension == 3:
                planes += [(1, 0.5 * self.size_y), (1, -0.5 * self.size_y)]
            if self.kind == "hele-shaw":
                planes += [(1, 0.5 * self.gap), (1, -0.5 * self.gap)]
        for i, (p, ri) in enumerate(zip(pos, r)):
            for axis, w in planes:
                if abs(abs(w - p[axis]) - ri) <= tol * ri:
                    q = p.copy()
                    q[axis] = w
                    out[i].append(q)
            if self.kind == "cylinder":
                rho = np.hypot(p[0], p[1])
                if abs(self.radius - rho - ri) <= tol * ri and rho > 0:
                    q = p.copy()
                    q[0] *= self.radius / rho
                    q[1] *= self.radius / rho
                    out[i].append(q)
        return out

    # ---- lateral extent -------------------------------------------------------------------------

    def lateral_bounds(self, pos: np.ndarray, r: np.ndarray):
        """(lo, hi) arrays over the lateral coordinates of coords(): the container's footprint, or the
        packing's bounding box where the container is open."""
        c = self.coords(pos)
        nlat = c.shape[1] - 1
        lo = (c[:, :nlat] - r[:, None]).min(axis=0) if len(c) else np.zeros(nlat)
        hi = (c[:, :nlat] + r[:, None]).max(axis=0) if len(c) else np.zeros(nlat)
        if self.kind in ("box", "periodic"):
            half = [0.5 * self.size_x] + ([0.5 * self.size_y] if self.dimension == 3 else [])
            return -np.array(half), np.array(half)
        if self.kind == "hele-shaw":
            return np.array([-0.5 * self.size_x, -0.5 * self.gap]), np.array([0.5 * self.size_x, 0.5 * self.gap])
        if self.kind == "cylinder":
            return np.array([-self.radius] * 2), np.array([self.radius] * 2)
        return lo, hi

    def inside(self, pos: np.ndarray) -> np.ndarray:
        """Which points (x, y, z) lie inside the container (above the floor, inside the walls)."""
        ok = pos[:, 2] >= 0.0
        if self.kind == "periodic":
            return ok
        return ok & (self.wall_distance(pos) >= 0.0)


def _nearest_image(delta: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """delta (..., len(periods)) with each periodic component reduced to its nearest image."""
    delta = np.array(delta, dtype=float, copy=True)
    for k, length in enumerate(periods):
        if length > 0:
            delta[..., k] -= length * np.round(delta[..., k] / length)
    return delta
