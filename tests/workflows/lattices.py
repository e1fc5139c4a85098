"""Configurations with known answers, built independently of the code under test."""
import numpy as np


def simple_cubic(n_xy: int, n_z: int, d: float = 1.0):
    """Simple-cubic spheres of diameter d touching their 6 neighbours, centres in the periodic
    domain [-L/2, L/2) (L = n_xy d), the lowest layer on the floor."""
    g = (np.arange(n_xy) + 0.5) * d - 0.5 * n_xy * d
    x, y, z = np.meshgrid(g, g, (np.arange(n_z) + 0.5) * d, indexing="ij")
    pos = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    return pos, np.full(len(pos), 0.5 * d), n_xy * d


def fcc(n_cells: int, n_z_cells: int, d: float = 1.0):
    """FCC spheres of diameter d (cubic cell a = sqrt(2) d, 12 touching neighbours), periodic
    laterally with L = n_cells a, the lowest layer on the floor."""
    a = np.sqrt(2.0) * d
    basis = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]]) * a
    cells = np.array([[i, j, k] for i in range(n_cells) for j in range(n_cells) for k in range(n_z_cells)]) * a
    pos = (cells[:, None, :] + basis[None, :, :]).reshape(-1, 3)
    L = n_cells * a
    pos[:, 0] -= 0.5 * L
    pos[:, 1] -= 0.5 * L
    pos[:, 2] += 0.5 * d
    return pos, np.full(len(pos), 0.5 * d), L


def square_2d(n_x: int, n_z: int, d: float = 1.0):
    """Disks in the x-z plane on a square lattice (4 neighbours), periodic in x."""
    x, z = np.meshgrid((np.arange(n_x) + 0.5) * d - 0.5 * n_x * d, (np.arange(n_z) + 0.5) * d, indexing="ij")
    pos = np.column_stack([x.ravel(), np.zeros(x.size), z.ravel()])
    return pos, np.full(len(pos), 0.5 * d), n_x * d


def hexagonal_2d(n_x: int, n_rows: int, d: float = 1.0):
    """Disks in the x-z plane on a triangular lattice (6 neighbours), periodic in x (n_x columns)."""
    rows = []
    for k in range(n_rows):
        x = (np.arange(n_x) + 0.5 * (k % 2)) * d - 0.5 * n_x * d
        rows.append(np.column_stack([x, np.zeros(n_x), np.full(n_x, 0.5 * d + k * d * np.sqrt(3) / 2)]))
    pos = np.vstack(rows)
    return pos, np.full(len(pos), 0.5 * d), n_x * d


def peaks(r, g, threshold=1.5):
    """Positions of the local maxima of g above threshold."""
    r, g = np.asarray(r), np.asarray(g)
    k = np.nonzero((g[1:-1] > g[:-2]) & (g[1:-1] >= g[2:]) & (g[1:-1] > threshold))[0] + 1
    return r[k]
