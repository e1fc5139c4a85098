"""The rows of the `settle-matrix` study (settle_matrix.py): each row's scene, made from one of the repository's
inputs with the row's changes and written as TOML.

Bed rows are inputs/bed3d.toml (polydisperse constant-mass radii 0.5-1 mm, r_max / r_min = 2, density 2500,
young 5e6, poisson 0.3, restitution 0.5) with the row's friction, rolling friction, radii or container, `count`
grains and a lateral size chosen so that the bed is about `depth` deep: bed3d's 10 000 grains in 3 cm x 3 cm
fill 2.9 cm at the packing fraction PHI_GUESS. Heap rows are inputs/heap3d.toml (a point source on an open floor)
and inputs/hele_shaw.toml with a plate distance of 5 and 15 grain diameters."""
from __future__ import annotations

import copy
import math
from pathlib import Path

from ..core.io import read_scene_toml, write_scene_toml
from ..core.runner import REPO

BED_BASE = REPO / "inputs" / "bed3d.toml"
HEAP_BASES = {"open-floor": REPO / "inputs" / "heap3d.toml", "hele-shaw": REPO / "inputs" / "hele_shaw.toml"}
PHI_GUESS = 0.6         # packing fraction assumed when sizing a bed (only its depth depends on it)
DEFAULT_COUNT = 3000
DEFAULT_DEPTH = 0.03    # m
DEFAULT_HEAP_COUNT = 2000
DEFAULT_YADE_COUNT = 1000

RATIO_1 = {"distribution": "constant", "value": 0.75e-3}
RATIO_4 = {"distribution": "constant-mass", "min": 0.25e-3, "max": 1.0e-3}

# name, label, kind ("bed" | "heap") and the changes to the base scene; run in this order (the base bed first, the
# costliest bed, ratio 4, last)
ROWS = (
    {"name": "bed_mu0.5", "label": "periodic bed, friction 0.5", "kind": "bed", "friction": 0.5},
    {"name": "bed_mu0.1", "label": "periodic bed, friction 0.1", "kind": "bed", "friction": 0.1},
    {"name": "bed_mu0.8", "label": "periodic bed, friction 0.8", "kind": "bed", "friction": 0.8},
    {"name": "bed_mu0.3", "label": "periodic bed, friction 0.3", "kind": "bed", "friction": 0.3},
    {"name": "bed_mu0.5_rolling0.1", "label": "periodic bed, friction 0.5, rolling friction 0.1", "kind": "bed",
     "friction": 0.5, "rolling_friction": 0.1},
    {"name": "bed_ratio1", "label": "periodic bed, monodisperse r = 0.75 mm, friction 0.5", "kind": "bed",
     "friction": 0.5, "radius": RATIO_1},
    {"name": "cylinder_ratio2", "label": "cylinder (rain), ratio 2, friction 0.5", "kind": "bed", "friction": 0.5,
     "container": "cylinder"},
    {"name": "bed_ratio4", "label": "periodic bed, constant-mass 0.25-1 mm (ratio 4), friction 0.5", "kind": "bed",
     "friction": 0.5, "radius": RATIO_4},
    {"name": "heap_open_floor", "label": "heap: point source on an open floor", "kind": "heap", "base": "open-floor"},
    {"name": "heap_hele_shaw_5d", "label": "heap: Hele-Shaw cell, gap 5 d", "kind": "heap", "base": "hele-shaw",
     "gap_d": 5},
    {"name": "heap_hele_shaw_15d", "label": "heap: Hele-Shaw cell, gap 15 d", "kind": "heap", "base": "hele-shaw",
     "gap_d": 15},
    # The same cells with Hertz contacts: settle refuses linear (Hooke) contacts' heaps, whose angle follows the
    # stiffness its softened calibration changes (coupling/dem/settle_plan.h).
    {"name": "heap_hele_shaw_5d_hertz", "label": "heap: Hele-Shaw cell, gap 5 d, Hertz contacts", "kind": "heap",
     "base": "hele-shaw", "gap_d": 5, "model": "hertz"},
    {"name": "heap_hele_shaw_15d_hertz", "label": "heap: Hele-Shaw cell, gap 15 d, Hertz contacts", "kind": "heap",
     "base": "hele-shaw", "gap_d": 15, "model": "hertz"},
)
# The optional YADE row: the base bed with fewer grains (--yade-count).
YADE_ROW = {"name": "bed_mu0.5_yade", "label": "periodic bed, friction 0.5, YADE", "kind": "bed", "friction": 0.5,
            "engine": "yade"}


def mean_cube_radius(radius: dict) -> float:
    """E[R^3] of a radius table (constant, uniform, constant-mass). Constant-mass, R = ab / w with w uniform in
    [a, b]: E[R^3] = (ab)^3 E[w^-3] = ab (a + b) / 2."""
    kind = radius["distribution"]
    if kind == "constant":
        return float(radius["value"]) ** 3
    a, b = float(radius["min"]), float(radius["max"])
    if kind == "uniform":
        return (b ** 4 - a ** 4) / (4.0 * (b - a))
    if kind == "constant-mass":
        return a * b * (a + b) / 2.0
    raise ValueError(f"mean_cube_radius: no formula for the {kind!r} distribution")


def footprint_area(count: int, depth: float, radius: dict, phi: float = PHI_GUESS) -> float:
    """The floor area [m^2] that `count` grains fill to `depth` at packing fraction phi."""
    return count * 4.0 / 3.0 * math.pi * mean_cube_radius(radius) / (phi * depth)


def largest_radius(radius: dict) -> float:
    return float(radius["value"] if radius["distribution"] == "constant" else radius["max"])


def bed_scene(row: dict, count: int, depth: float) -> dict:
    scene = copy.deepcopy(read_scene_toml(BED_BASE))
    scene["scene"]["name"] = row["name"]
    grains = scene["grains"]
    grains["count"] = int(count)
    if "radius" in row:
        grains["radius"] = dict(row["radius"])
    scene["material"]["friction"] = float(row["friction"])
    scene["material"]["rolling_friction"] = float(row.get("rolling_friction", 0.0))
    area = footprint_area(count, depth, grains["radius"])
    if row.get("container", "periodic") == "cylinder":
        scene["container"] = {"kind": "cylinder", "radius": math.sqrt(area / math.pi)}
    else:
        side = math.sqrt(area)
        scene["container"] = {"kind": "periodic", "size": [side, side]}
    if "engine" in row:
        scene["relax"]["engine"] = row["engine"]
    return scene


def heap_scene(row: dict, count: int) -> dict:
    scene = copy.deepcopy(read_scene_toml(HEAP_BASES[row["base"]]))
    scene["scene"]["name"] = row["name"]
    scene["grains"]["count"] = int(count)
    if "gap_d" in row:
        r = largest_radius(scene["grains"]["radius"])
        gap = row["gap_d"] * 2.0 * r
        scene["container"]["gap"] = gap
        half = gap / 2.0 - r  # the pouring box spans the gap less one radius on each side, as in hele_shaw.toml
        scene["source"]["y"] = [-half, half]
    if "model" in row:
        scene["relax"]["model"] = row["model"]
    return scene


def row_scene(row: dict, count: int, depth: float) -> dict:
    return bed_scene(row, count, depth) if row["kind"] == "bed" else heap_scene(row, count)


def write_row_scene(folder, row: dict, count: int, depth: float) -> str:
    """FOLDER/<row name>.toml; returns its path."""
    path = Path(folder) / f"{row['name']}.toml"
    scene = row_scene(row, count, depth)
    header = (f"# settle-matrix row {row['name']}: {row['label']} ({count} grains"
              + (f", a bed about {depth * 100:g} cm deep at packing fraction {PHI_GUESS:g})" if row["kind"] == "bed"
                 else ")") + "; written by workflows/btrdem/studies/settle_rows.py\n")
    write_scene_toml(path, scene)
    path.write_text(header + path.read_text())
    return str(path)


def matrix_rows(count: int = DEFAULT_COUNT, heap_count: int = DEFAULT_HEAP_COUNT, yade_count: int = 0,
                only=None) -> list:
    """The rows to run, each with its grain count; only: names to keep (None: all)."""
    rows = [dict(r, count=count if r["kind"] == "bed" else heap_count) for r in ROWS]
    if yade_count:
        rows.append(dict(YADE_ROW, count=yade_count))
    if only:
        unknown = sorted(set(only) - {r["name"] for r in rows})
        if unknown:
            raise ValueError(f"unknown row(s) {', '.join(unknown)}; expected some of "
                             f"{', '.join(r['name'] for r in rows)}")
        rows = [r for r in rows if r["name"] in only]
    return rows
