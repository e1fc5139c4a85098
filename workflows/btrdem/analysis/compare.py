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

from . import measures

from ..core import report
from .displacement import displacement, displacement_stats, local_displacement, mean_diameter
from ..core.geometry import Container
from ..core.io import (InputError, Packing, atomic_write_text, read_packing, read_scene_toml, write_json, write_packing,
                 write_vtp)
from .nonphysical import THRESHOLDS, nonphysical, nonphysical_md
from .support import btr_supports

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
    """PRE without the grains a relaxation or a pour on an open floor removed (POST's JSON relax.removed.ids or
    pour.removed.ids, ids of PRE), renumbered 1..M as `btr relax` and `btr pour` renumber POST; PRE itself when
    nothing was removed."""
    run = post.meta.get("relax") or post.meta.get("pour") or {}
    removed = (run.get("removed") or {}).get("ids") or []
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
            margin: float | None = None, tol: float | None = None,
            progress=print, local_reach_d: float = LOCAL_REACH_D) -> dict:
    """margin, tol: bulk-window margin (largest diameters) and contact tolerance of `btr measure`;
    None keeps its defaults."""
    out = Path(outdir)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    pre = read_packing(pre_path)
    post = read_packing(post_path)
    kept = without_removed(pre, post)
    if kept is not pre:  # measure the grains POST still has, under the ids POST uses
        pre_path = write_packing(out, "pre_kept", kept, vtp=False)["csv"]
        pre = kept
    align(pre, post)
    container, scene = load_context(pre, scene_path)
    d = mean_diameter(pre.radius)

    progress(f"compare: {len(pre)} grains, {container.dimension}D {container.kind} container, d = {d:.4g} m")
    disp_vec = displacement(pre.pos, post.pos, container)
    disp_d = np.linalg.norm(disp_vec, axis=1) / d
    stats = displacement_stats(disp_d, THRESHOLDS)
    local_d = local_displacement(pre.pos, disp_vec, container, local_reach_d * d) / d
    stats_local = displacement_stats(local_d, THRESHOLDS)

    progress("compare: structure of PRE and POST (btr measure)")
    s_pre = measures.measure(pre_path, margin, tol, scene_path, per_grain=True, out_json=out / "pre.measures.json")
    s_post = measures.measure(post_path, margin, tol, scene_path, out_json=out / "post.measures.json")
    per_grain = s_pre.pop("per_grain")
    if not np.array_equal(per_grain["id"], pre.ids):
        raise InputError(f"{pre_path}: btr measure's per-grain ids differ from the packing's")

    progress("compare: BTR supports of the grains DEM moved")
    sup = btr_supports(pre.pos, pre.radius, container)
    height_d = pre.pos[:, 2] / d
    wall_d = container.wall_distance(pre.pos) / d
    surface_d = per_grain["surface_depth"] / d
    nonphys = {"absolute": nonphysical(sup, disp_d, height_d, wall_d, surface_d, container.dimension),
               "local": nonphysical(sup, local_d, height_d, wall_d, surface_d, container.dimension)}

    def delta(f):
        a, b = f(s_pre), f(s_post)
        return None if a is None or b is None else b - a

    changes = {
        "packing_fraction": delta(measures.packing_fraction),
        "coordination_mean": delta(measures.coordination),
        "rdf_rms_difference": measures.rdf_distance(measures.rdf(s_pre)[1], measures.rdf(s_post)[1],
                                                    measures.rdf(s_pre)[0]),
        "angle_of_repose_deg": delta(measures.angle_of_repose),
        "segregation_index": delta(measures.segregation),
    }
    heap = s_pre["heap"]["axis"] if s_pre.get("heap") else None

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
    figs["rdf"] = report.curves(figdir / "rdf.png", [("BTR (pre)", *measures.rdf(s_pre)),
                                                     ("relaxed (post)", *measures.rdf(s_post))],
                                "r / mean diameter", "g(r)", "Radial distribution function (bulk window)")
    sp, sq = measures.surface_profile(s_pre), measures.surface_profile(s_post)
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
    aor = [measures.angle_of_repose(s) for s in (sp, sq)]
    seg = [measures.segregation(s) for s in (sp, sq)]
    lines = [f"# Comparison: {os.path.basename(res['pre'])} -> {os.path.basename(res['post'])}", "",
             f"{sp['n_grains']} grains, {res['dimension']}D, container {res['container']['kind']}, mean diameter "
             f"d = {report.fmt(res['mean_diameter'])} m. Measures by `btr measure` (the numbers btr.json and "
             f"relaxed.json hold): {measures.definitions(sp)}.", "",
             "## Structure", ""]
    margin_d, tol = sp["bulk"]["window_margin_diameters"], sp["bulk"]["contact_tolerance"]
    rows = [["bulk grains", sp["bulk"].get("grains_in_window"), sq["bulk"].get("grains_in_window"), None],
            [f"packing fraction (bulk, margin {margin_d:g} d_max)", measures.packing_fraction(sp), measures.packing_fraction(sq),
             ch["packing_fraction"]],
            [f"mean coordination (bulk, contact tolerance {tol:g})", measures.coordination(sp), measures.coordination(sq), ch["coordination_mean"]],
            [f"mean coordination (all grains, contact tolerance {tol:g})", sp["mean_coordination_all_grains"], sq["mean_coordination_all_grains"],
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
    dp = measures.coordination_distribution(sp) or {}
    dq = measures.coordination_distribution(sq) or {}
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
    lines += nonphysical_md(res["nonphysical"]["local"], "by local displacement")
    lines += nonphysical_md(res["nonphysical"]["absolute"], "by displacement")
    lines += ["## Figures", ""]
    for k, v in res["files"].items():
        if v.endswith(".png"):
            lines.append(f"![{k}](figures/{os.path.basename(v)})")
    lines += ["", "ParaView: open pre_displacement.vtp (BTR positions) or post_displacement.vtp (relaxed), apply a "
              "Glyph filter (sphere, scale by 'radius', factor 2 for diameter) and colour by 'displacement'.", ""]
    return "\n".join(lines)
