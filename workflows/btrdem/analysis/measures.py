"""Structural measures of a packing, from `btr measure` (btr/measures/metrics.cpp is their one definition).

Bulk window, packing fraction, coordination and its histogram, g(r), the heap angle and surface profile,
the segregation index and heights are computed by the C++ library, exactly as `btr deposit` stores them
in NAME.json and `btr relax` in relaxed.json, so the workflows' tables agree with those files to the
last digit. This module runs the program and reads its JSON; it computes no measure of its own.
Comparisons of two measures (e.g. rdf_distance) live here too."""
from __future__ import annotations

import csv
import json
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from ..core.io import read_json
from ..core.runner import StepFailed, find_btr


def measure(packing_csv, margin: float | None = None, contact_tolerance: float | None = None,
            scene_toml: str | None = None, per_grain: bool = False, out_json=None, btr: str | None = None) -> dict:
    """`btr measure PACKING.csv` -> the measures dict (the "measures" object of btr.json).
    margin / contact_tolerance: None keeps the program's defaults (the one default, named in the output).
    per_grain=True adds "per_grain": {"id", "coordination", "in_window", "surface_depth"} arrays.
    out_json: also keep the JSON there (default: not kept)."""
    btr = btr or find_btr()
    packing_csv = Path(packing_csv)
    argv = [btr, "measure", str(packing_csv)]
    if out_json:
        argv += ["-o", str(out_json)]
    if margin is not None:
        argv += ["--margin", repr(float(margin))]
    if contact_tolerance is not None:
        argv += ["--contact-tolerance", repr(float(contact_tolerance))]
    if scene_toml:
        argv += ["--scene", str(scene_toml)]
    with tempfile.TemporaryDirectory(prefix="btr_measure_") as tmp:
        grain_csv = Path(tmp) / "per_grain.csv"
        if per_grain:
            argv += ["--per-grain", str(grain_csv)]
        p = subprocess.run([str(a) for a in argv], capture_output=True, text=True)
        if p.returncode != 0:
            raise StepFailed(f"btr measure {packing_csv}: exit status {p.returncode}: {p.stderr.strip()[-2000:]}")
        m = read_json(out_json) if out_json else json.loads(p.stdout)
        if per_grain:
            with open(grain_csv, newline="") as f:
                rows = list(csv.DictReader(f))
            m["per_grain"] = {"id": np.array([int(r["id"]) for r in rows]),
                              "coordination": np.array([int(r["coordination"]) for r in rows]),
                              "in_window": np.array([r["in_window"] == "1" for r in rows]),
                              "surface_depth": np.array([float(r["surface_depth"]) for r in rows])}
    return m


# ---- reading single numbers out of a measures dict (None where the measure does not exist) ----

def packing_fraction(m: dict):
    return m["bulk"].get("packing_fraction")


def coordination(m: dict):
    return m["bulk"].get("mean_coordination")


def angle_of_repose(m: dict):
    h = m.get("heap")
    return h.get("angle_of_repose_deg") if h else None


def segregation(m: dict):
    s = m.get("segregation")
    return s.get("index") if s and s.get("valid") else None


def rdf(m: dict):
    """(r / d, g) or (None, None)."""
    g = m.get("rdf")
    return (g["r_over_d"], g["g"]) if g else (None, None)


def coordination_distribution(m: dict) -> dict | None:
    """{"k": fraction of the window's grains with k contacts}."""
    h = m["bulk"].get("coordination_histogram")
    if not h:
        return None
    n = sum(h)
    return {str(k): c / n for k, c in enumerate(h)}


def surface_profile(m: dict) -> dict:
    """{"mode", "coord", "height"}: against the distance from the heap axis for point sources, else x."""
    if m.get("heap"):
        return dict(m["heap"]["profile"], mode="radial")
    return dict(m["surface_profile_x"], mode="x")


def definitions(m: dict) -> str:
    """One sentence naming the window and the contact rule the numbers were taken with."""
    b = m["bulk"]
    return (f"bulk window {b['window_margin_diameters']:g} largest diameters from the floor, walls and free surface; "
            f"contact: gap < {b['contact_tolerance']:g} x smaller radius")


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
