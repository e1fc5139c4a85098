"""`compare PRE POST`: two packings of the same grains (same ids), e.g. BTR and its DEM relaxation.

Writes into OUTDIR: compare.json (every number), compare.md (tables), per_grain.csv, figures/*.png
(displacement histogram, displacement against height, g(r) and surface profile before/after, kinetic
energy if POST's folder has kinetic.csv), and pre_displacement.vtp / post_displacement.vtp (the
grains at their BTR and relaxed positions with the displacement as point data, for ParaView)."""
from __future__ import annotations

import csv
import dataclasses
import os
from pathlib import Path

import numpy as np

from . import metrics, report
from .geometry import Container
from .io import InputError, Packing, atomic_write_text, read_packing, read_scene_toml, write_json, write_vtp
from .support import KIND_LABEL, KIND_ORDER, btr_supports

THRESHOLDS = (0.1, 0.5)
LOCAL_REACH_D = 2.0  # neighbourhood of the local (relative) displacement, in mean diameters


def load_context(pre: Packing, scene_path: str | None):
    """(container, scene dict) from the scene file if given, else from PRE's JSON."""
    if scene_path:
        scene = read_scene_toml(scene_path)
        try:
            dim = int(scene["scene"]["dimension"])
            container = Container.from_json(scene["container"], dim, origin=scene_path)
        except KeyError as e:
            raise InputError(f"{scene_path}: missing key {e}") from None
        except ValueError as e:
            raise InputError(str(e)) from None
        return container, scene
    try:
        return pre.container(), pre.scene()
    except ValueError as e:
        raise InputError(str(e)) from None


def without_removed(pre: Packing, post: Packing) -> Packing:
    """PRE without the grains a relaxation on an open floor removed (POST's JSON relax.removed.ids, ids of
    PRE), renumbered 1..M as `btr relax` renumbers POST; PRE itself when nothing was removed."""
    removed = ((post.meta.get("relax") or {}).get("removed") or {}).get("ids") or []
    if not removed:
        return pre
    keep = ~np.isin(pre.ids, np.asarray(removed, dtype=np.int64))
    return dataclasses.replace(pre, ids=np.arange(1, int(keep.sum()) + 1, dtype=pre.ids.dtype), pos=pre.pos[keep],
                               radius=pre.radius[keep], species=pre.species[keep])


def align(pre: Packing, post: Packing):
    if len(pre) != len(post) or not np.array_equal(pre.ids, post.ids):
        missing = np.setdiff1d(pre.ids, post.ids)
        extra = np.setdiff1d(post.ids, pre.ids)
        raise InputError(f"{post.path}: expected the same grain ids as {pre.path} ({len(pre)} grains); "
                         f"missing {missing[:10].tolist()}{'...' if len(missing) > 10 else ''}, "
                         f"extra {extra[:10].tolist()}{'...' if len(extra) > 10 else ''}")
    if not np.allclose(pre.radius, post.radius, rtol=1e-9):
        i = int(np.argmax(np.abs(pre.radius - post.radius)))
        raise InputError(f"{post.path}: grain {pre.ids[i]}: expected the radius {pre.radius[i]:.6g} of {pre.path}, "
                         f"got {post.radius[i]:.6g}")


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


def read_kinetic(path: str):
    """kinetic.csv (time, kinetic energy) as arrays, or None."""
    if not os.path.exists(path):
        return None
    try:
        a = np.genfromtxt(path, delimiter=",", names=True)
    except ValueError:
        return None
    if a.size == 0 or a.dtype.names is None or len(a.dtype.names) < 2:
        return None
    names = a.dtype.names
    return np.atleast_1d(a[names[0]]), np.atleast_1d(a[names[1]]), names


def compare(pre_path: str, post_path: str, outdir: str, scene_path: str | None = None,
            window: metrics.Window = metrics.Window(), tol: float = metrics.CONTACT_TOLERANCE,
            progress=print, local_reach_d: float = LOCAL_REACH_D) -> dict:
    out = Path(outdir)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    pre = read_packing(pre_path)
    post = read_packing(post_path)
    pre = without_removed(pre, post)
    align(pre, post)
    container, scene = load_context(pre, scene_path)
    heap = metrics.heap_axis_of(scene)
    d = metrics.mean_diameter(pre.radius)

    progress(f"compare: {len(pre)} grains, {container.dimension}D {container.kind} container, d = {d:.4g} m")
    disp_vec = metrics.displacement(pre.pos, post.pos, container)
    disp_d = np.linalg.norm(disp_vec, axis=1) / d
    stats = metrics.displacement_stats(disp_d, THRESHOLDS)
    local_d = metrics.local_displacement(pre.pos, disp_vec, container, local_reach_d * d) / d
    stats_local = metrics.displacement_stats(local_d, THRESHOLDS)

    progress("compare: structure of PRE")
    s_pre = metrics.structure(pre.pos, pre.radius, pre.species, container, d, window, heap, tol)
    progress("compare: structure of POST")
    s_post = metrics.structure(post.pos, post.radius, post.species, container, d, window, heap, tol)

    progress("compare: BTR supports of the grains DEM moved")
    sup = btr_supports(pre.pos, pre.radius, container)
    bulk_pre = metrics.Bulk(pre.pos, pre.radius, container, window, d)
    height_d = pre.pos[:, 2] / d
    wall_d = container.wall_distance(pre.pos) / d
    surface_d = bulk_pre.surface_distance() / d
    nonphys = {"absolute": nonphysical(sup, disp_d, height_d, wall_d, surface_d, container.dimension),
               "local": nonphysical(sup, local_d, height_d, wall_d, surface_d, container.dimension)}

    def delta(a, b):
        return None if a is None or b is None else b - a

    aor = [s["angle_of_repose"]["angle_deg"] if s["angle_of_repose"] else None for s in (s_pre, s_post)]
    seg = [s["segregation"]["index"] if s["segregation"] else None for s in (s_pre, s_post)]
    changes = {
        "packing_fraction": delta(s_pre["packing_fraction"], s_post["packing_fraction"]),
        "coordination_mean": delta(s_pre["coordination"]["mean"], s_post["coordination"]["mean"]),
        "rdf_rms_difference": metrics.rdf_distance(s_pre["rdf"]["g"], s_post["rdf"]["g"], s_pre["rdf"]["r_over_d"]),
        "angle_of_repose_deg": delta(*aor),
        "segregation_index": delta(*seg),
    }

    progress("compare: figures and VTK files")
    figs = _figures(out / "figures", disp_d, local_d, height_d, s_pre, s_post, post_path)
    point_data = {"displacement": disp_d, "local_displacement": local_d, "displacement_vector": disp_vec,
                  "moved": (disp_d > THRESHOLDS[0]) * 1.0, "moved_locally": (local_d > THRESHOLDS[0]) * 1.0,
                  "n_supports": sup["n_supports"], "edge_distance": sup["edge_distance"]}
    write_vtp(out / "pre_displacement.vtp", pre, point_data)
    write_vtp(out / "post_displacement.vtp", post, point_data)
    _write_per_grain(out / "per_grain.csv", pre, disp_d, local_d, sup, height_d, wall_d, surface_d)

    result = {"pre": os.path.abspath(pre_path), "post": os.path.abspath(post_path),
              "scene": os.path.abspath(scene_path) if scene_path else None,
              "dimension": container.dimension, "container": container.__dict__, "heap_axis": heap,
              "mean_diameter": d, "displacement_d": stats, "local_displacement_d": stats_local,
              "local_reach_d": local_reach_d, "structure": {"pre": s_pre, "post": s_post},
              "changes": changes, "nonphysical": nonphys,
              "files": dict(figs, compare_md=str(out / "compare.md"), per_grain=str(out / "per_grain.csv"),
                            pre_vtp=str(out / "pre_displacement.vtp"), post_vtp=str(out / "post_displacement.vtp"))}
    write_json(out / "compare.json", result)
    atomic_write_text(out / "compare.md", markdown(result))
    progress(f"compare: wrote {out / 'compare.md'}")
    return result


def _figures(figdir: Path, disp_d, local_d, height_d, s_pre, s_post, post_path) -> dict:
    figs = {"displacement_histogram": report.displacement_histogram(disp_d, figdir / "displacement_histogram.png",
                                                                    local=local_d),
            "displacement_vs_height": report.displacement_vs_height(height_d, disp_d, figdir / "displacement_vs_height.png",
                                                                    disp_d > THRESHOLDS[0], local=local_d)}
    figs["rdf"] = report.curves(figdir / "rdf.png", [("BTR (pre)", s_pre["rdf"]["r_over_d"], s_pre["rdf"]["g"]),
                                                     ("relaxed (post)", s_post["rdf"]["r_over_d"], s_post["rdf"]["g"])],
                                "r / mean diameter", "g(r)", "Radial distribution function (bulk window)")
    sp, sq = s_pre["surface_profile"], s_post["surface_profile"]
    xl = "distance from the heap axis [m]" if sp["mode"] == "radial" else "x [m]"
    figs["surface_profile"] = report.curves(figdir / "surface_profile.png",
                                            [("BTR (pre)", sp["coord"], sp["height"]),
                                             ("relaxed (post)", sq["coord"], sq["height"])],
                                            xl, "top of the packing [m]", "Free-surface profile")
    kin = read_kinetic(os.path.join(os.path.dirname(os.path.abspath(post_path)), "kinetic.csv"))
    if kin is not None:
        t, e, names = kin
        pos = e > 0
        figs["kinetic_energy"] = report.curves(figdir / "kinetic_energy.png", [("kinetic energy", t[pos], e[pos])],
                                               f"{names[0]}", f"{names[1]}", "Kinetic energy during relaxation",
                                               logy=True)
    return figs


def _write_per_grain(path, pre, disp_d, local_d, sup, height_d, wall_d, surface_d):
    rows = ["id,displacement_d,local_displacement_d,n_supports,support_kind,edge_distance_r,offset_r,load,height_d,wall_distance_d,"
            "surface_distance_d"]
    for k in range(len(pre)):
        rows.append(",".join([str(int(pre.ids[k])), f"{disp_d[k]:.9g}", f"{local_d[k]:.9g}", str(int(sup["n_supports"][k])),
                              sup["kind"][k], f"{sup['edge_distance'][k]:.6g}", f"{sup['offset'][k]:.6g}",
                              str(int(sup["load"][k])), f"{height_d[k]:.6g}", f"{wall_d[k]:.6g}",
                              f"{surface_d[k]:.6g}"]))
    atomic_write_text(path, "\n".join(rows) + "\n")


def markdown(res: dict) -> str:
    sp, sq = res["structure"]["pre"], res["structure"]["post"]
    st, ch = res["displacement_d"], res["changes"]
    aor = [s["angle_of_repose"]["angle_deg"] if s["angle_of_repose"] else None for s in (sp, sq)]
    seg = [s["segregation"]["index"] if s["segregation"] else None for s in (sp, sq)]
    lines = [f"# Comparison: {os.path.basename(res['pre'])} -> {os.path.basename(res['post'])}", "",
             f"{sp['n_grains']} grains, {res['dimension']}D, container {res['container']['kind']}, mean diameter "
             f"d = {report.fmt(res['mean_diameter'])} m. Bulk window: {sp['window']['floor']:g} d above the floor, "
             f"{sp['window']['wall']:g} d from walls, {sp['window']['surface']:g} d below the free surface; "
             f"contacts: centre distance < (r_i + r_j)(1 + {sp['window']['contact_tolerance']:g}).", "",
             "## Structure", ""]
    rows = [["bulk grains", sp["window"]["n_bulk_grains"], sq["window"]["n_bulk_grains"], None],
            ["packing fraction (bulk)", sp["packing_fraction"], sq["packing_fraction"], ch["packing_fraction"]],
            ["mean coordination (bulk)", sp["coordination"]["mean"], sq["coordination"]["mean"], ch["coordination_mean"]],
            ["mean coordination (all grains)", sp["coordination"]["mean_all_grains"], sq["coordination"]["mean_all_grains"],
             None],
            ["g(r) RMS difference (r > 0.5 d)", None, None, ch["rdf_rms_difference"]],
            ["angle of repose [deg]", aor[0], aor[1], ch["angle_of_repose_deg"]],
            ["segregation index", seg[0], seg[1], ch["segregation_index"]],
            ["top of packing [m]", sp["height"]["max_top"], sq["height"]["max_top"], None]]
    lines.append(report.md_table(["measure", "pre (BTR)", "post (relaxed)", "change"],
                                 [[r[0]] + [report.fmt(x) if x is not None else ("" if k == 3 else "n/a")
                                            for k, x in enumerate(r[1:], 1)] for r in rows]))
    lines += ["## Displacement (mean diameters)", "",
              report.md_table(["mean", "median", "95th percentile", "max", "fraction > 0.1 d", "fraction > 0.5 d"],
                              [[st["mean"], st["median"], st["p95"], st["max"], st["fraction_above_0.1"],
                                st["fraction_above_0.5"]]])]
    dp = sp["coordination"]["distribution"] or {}
    dq = sq["coordination"]["distribution"] or {}
    ks = sorted(set(dp) | set(dq), key=int)
    if ks:
        lines += ["## Contact-number distribution (bulk, fraction of grains)", "",
                  report.md_table(["contacts"] + ks, [["pre"] + [dp.get(k, 0.0) for k in ks],
                                                      ["post"] + [dq.get(k, 0.0) for k in ks]])]
    lt = res["local_displacement_d"]
    lines += [f"Local displacement (the displacement minus the mean of the grains within {res['local_reach_d']:g} d, "
              "which removes settling of the bed as a whole, e.g. elastic compression):", "",
              report.md_table(["mean", "median", "95th percentile", "max", "fraction > 0.1 d", "fraction > 0.5 d"],
                              [[lt["mean"], lt["median"], lt["p95"], lt["max"], lt["fraction_above_0.1"],
                                lt["fraction_above_0.5"]]])]
    lines += _nonphysical_md(res["nonphysical"]["local"], "by local displacement")
    lines += _nonphysical_md(res["nonphysical"]["absolute"], "by displacement")
    lines += ["## Figures", ""]
    for k, v in res["files"].items():
        if v.endswith(".png"):
            lines.append(f"![{k}](figures/{os.path.basename(v)})")
    lines += ["", "ParaView: open pre_displacement.vtp (BTR positions) or post_displacement.vtp (relaxed), apply a "
              "Glyph filter (sphere, scale by 'radius', factor 2 for diameter) and colour by 'displacement'.", ""]
    return "\n".join(lines)


def _nonphysical_md(npx: dict, which: str) -> list:
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
