"""Nonphysical BTR configurations: where the grains DEM moved are (height, depth below the free surface,
distance from walls) and what their BTR support was, tabulated against the fraction moved; the bins
that move at least twice as often as the whole packing are the configurations DEM rejects."""
from __future__ import annotations

import numpy as np

from ..core import report
from .support import KIND_LABEL, KIND_ORDER

THRESHOLDS = (0.1, 0.5)  # displacement thresholds, in mean diameters


def _binned(values, moved_lo, moved_hi, edges, label_unit):
    """Rows (bin, grains, fraction moved > 0.1 d, > 0.5 d) of a quantity split at `edges`."""
    rows = []
    values = np.asarray(values, dtype=float)
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (values >= lo) & (values < hi)
        n = int(np.count_nonzero(sel))
        if n == 0:
            continue
        lo_s = "-inf" if np.isinf(lo) else f"{lo:g}"
        hi_s = "inf" if np.isinf(hi) else f"{hi:g}"
        rows.append({"bin": f"[{lo_s}, {hi_s}) {label_unit}", "grains": n,
                     "moved_0.1": float(np.mean(moved_lo[sel])), "moved_0.5": float(np.mean(moved_hi[sel]))})
    return rows


def nonphysical(sup: dict, disp_d, height_d, wall_d, surface_d, dimension: int) -> dict:
    """Where the grains DEM moved are and what their BTR support was."""
    lo, hi = disp_d > THRESHOLDS[0], disp_d > THRESHOLDS[1]
    overall = float(np.mean(lo))
    by_kind = []
    for k in KIND_ORDER:
        sel = sup["kind"] == k
        n = int(np.count_nonzero(sel))
        if n == 0:
            continue
        e = sup["edge_distance"][sel]
        e = e[np.isfinite(e)]
        by_kind.append({"kind": k, "label": KIND_LABEL[k], "grains": n, "moved_0.1": float(np.mean(lo[sel])),
                        "moved_0.5": float(np.mean(hi[sel])),
                        "median_edge_distance": float(np.median(e)) if len(e) else None,
                        "with_wall": int(np.count_nonzero(sup["walls"][sel] > 0))})
    edge_edges = [-np.inf, 0.0, 0.05, 0.1, 0.2, 0.4, np.inf]
    finite = np.isfinite(sup["edge_distance"])
    tables = {
        "by_support": by_kind,
        "by_edge_distance": _binned(np.where(finite, sup["edge_distance"], np.nan), lo, hi, edge_edges, "r"),
        "by_height": _binned(height_d, lo, hi, [0, 1, 2, 5, 10, 20, np.inf], "d"),
        "by_surface_distance": _binned(surface_d, lo, hi, [-np.inf, 1, 2, 5, 10, np.inf], "d"),
    }
    if np.any(np.isfinite(wall_d)):
        tables["by_wall_distance"] = _binned(wall_d, lo, hi, [-np.inf, 1, 2, 5, np.inf], "d")

    def med(a, sel):
        a = np.asarray(a, dtype=float)[sel]
        a = a[np.isfinite(a)]
        return float(np.median(a)) if len(a) else None

    medians = {}
    for name, arr in (("height_d", height_d), ("wall_distance_d", wall_d), ("surface_distance_d", surface_d),
                      ("edge_distance_r", sup["edge_distance"]), ("n_supports", sup["n_supports"]),
                      ("load", sup["load"])):
        medians[name] = {"moved": med(arr, lo), "stayed": med(arr, ~lo)}
    # The configurations DEM rejects most: support kinds and edge-distance bins moving at least
    # twice as often as the packing as a whole (and at least 5 grains).
    flagged = []
    for table, key in (("by_support", "label"), ("by_edge_distance", "bin"), ("by_height", "bin"),
                       ("by_surface_distance", "bin"), ("by_wall_distance", "bin")):
        for row in tables.get(table, []):
            if row["grains"] >= 5 and row["moved_0.1"] >= max(2 * overall, 0.05) and row["moved_0.1"] > 0:
                flagged.append({"table": table, "bin": row[key], "grains": row["grains"],
                                "moved_0.1": row["moved_0.1"]})
    return {"thresholds_d": list(THRESHOLDS), "moved_0.1": overall, "moved_0.5": float(np.mean(hi)),
            "n_moved_0.1": int(np.count_nonzero(lo)), "medians": medians, "tables": tables, "rejected": flagged,
            "edge_distance_note": ("signed distance of the centre's projection from the edge of the support "
                                   "polygon (3 supports: triangle; 2: segment; 2D: interval along x), "
                                   "in grain radii, > 0 inside")}


def nonphysical_md(npx: dict, which: str) -> list:
    lines = [f"## Nonphysical BTR configurations: grains DEM moved ({which})", "",
             f"{npx['n_moved_0.1']} grains ({report.fmt(100 * npx['moved_0.1'], 3)} %) moved more than 0.1 d and "
             f"{report.fmt(100 * npx['moved_0.5'], 3)} % more than 0.5 d. Edge distance: {npx['edge_distance_note']}.",
             ""]
    if npx["rejected"]:
        lines += ["Configurations DEM rejects (moving at least twice as often as the packing as a whole):", ""]
        for f in npx["rejected"]:
            lines.append(f"- {f['table'].replace('by_', '').replace('_', ' ')} {f['bin']}: {f['grains']} grains, "
                         f"{report.fmt(100 * f['moved_0.1'], 3)} % moved > 0.1 d")
        lines.append("")
    else:
        lines += ["No support kind or location moves at least twice as often as the packing as a whole.", ""]
    lines.append(report.md_table(
        ["BTR support", "grains", "moved > 0.1 d", "moved > 0.5 d", "median edge distance / r", "touching a wall"],
        [[r["label"], r["grains"], r["moved_0.1"], r["moved_0.5"], r["median_edge_distance"], r["with_wall"]]
         for r in npx["tables"]["by_support"]]))
    titles = {"by_edge_distance": "edge distance of the support polygon", "by_height": "height of the centre",
              "by_surface_distance": "depth below the free surface", "by_wall_distance": "distance from the nearest wall"}
    for key, title in titles.items():
        rows = npx["tables"].get(key)
        if not rows:
            continue
        lines += [f"By {title}:", "", report.md_table(["bin", "grains", "moved > 0.1 d", "moved > 0.5 d"],
                                                      [[r["bin"], r["grains"], r["moved_0.1"], r["moved_0.5"]]
                                                       for r in rows])]
    lines += ["Medians, grains moved > 0.1 d vs the others:", "",
              report.md_table(["quantity", "moved", "stayed"],
                              [[k, v["moved"], v["stayed"]] for k, v in npx["medians"].items()])]
    return lines
