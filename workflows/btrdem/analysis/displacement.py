"""How far grains moved between two packings of the same grains (e.g. BTR and its relaxation)."""
from __future__ import annotations

import numpy as np

from ..core.geometry import Container
from ..core.neighbours import within


def mean_diameter(radius: np.ndarray) -> float:
    return float(2.0 * np.mean(radius))


def displacement(pre_pos: np.ndarray, post_pos: np.ndarray, container: Container) -> np.ndarray:
    """Displacement vectors (x, y, z), nearest periodic image for periodic containers."""
    return container.minimum_image_xyz(post_pos - pre_pos)


def local_displacement(pre_pos: np.ndarray, disp: np.ndarray, container: Container, reach: float) -> np.ndarray:
    """|u_i - mean of u_j over the grains j within `reach` of grain i (pre positions, i included)|:
    the part of a grain's displacement its neighbourhood did not share. A bed settling as a whole
    (elastic compression, a rigid shift) has large displacements but small local ones."""
    coords = container.coords(pre_pos)
    lists = within(coords, container, reach)
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
