"""The `settle-matrix` study's verdict arithmetic, report.md and figure (settle_matrix.py runs the rows).

A row's settled packing is judged per measure by its error in units of the reference pours' floor (their
seed-to-seed standard deviation s): error / s, and whether the error is within the reach threshold
2 s sqrt(1 + 1/n) of error_runtime.reach_threshold (n reference seeds)."""
from __future__ import annotations

import math

import numpy as np

from ..core import report
from .error_runtime import MEASURES, reach_threshold

BED_MEASURES = ("packing_fraction", "coordination", "rdf", "segregation")
HEAP_MEASURES = ("angle_of_repose",)
SHORT = {"packing_fraction": "phi", "coordination": "Z", "rdf": "g(r)", "segregation": "segregation",
         "angle_of_repose": "heap angle"}


def judge(errors: dict, floor: dict, n_seeds: int) -> dict:
    """Per measure: {error, error_over_floor (None where the floor is 0 or the error missing), within (error <= the
    reach threshold)}."""
    limit = reach_threshold(floor, n_seeds)
    out = {}
    for key, err in errors.items():
        if err is None:
            out[key] = {"error": None, "error_over_floor": None, "within": False}
            continue
        out[key] = {"error": float(err), "error_over_floor": float(err) / floor[key] if floor[key] > 0 else None,
                    "within": bool(err <= limit[key])}
    return out


def seed_summary(entries: list, ref: dict) -> dict:
    """Per measure of a bed row (packing fraction, coordination) over the settle seeds that finished: mean, sample
    standard deviation (None for one seed), the mean's error against the pours' mean and over their floor, and how
    many seeds were within the reach threshold."""
    done = [e for e in entries if e["status"] == "ok"]
    out = {"seeds": len(entries), "finished": len(done)}
    for key in ("packing_fraction", "coordination"):
        vals = [e["values"][key] for e in done if e["values"].get(key) is not None]
        if not vals or key not in ref["mean"]:
            continue
        mean = float(np.mean(vals))
        floor = ref["floor"][key]
        out[key] = {"mean": mean, "sd": float(np.std(vals, ddof=1)) if len(vals) > 1 else None,
                    "mean_error": mean - ref["mean"][key],
                    "mean_error_over_floor": (mean - ref["mean"][key]) / floor if floor > 0 else None,
                    "within": sum(bool(e["judged"][key]["within"]) for e in done if key in e["judged"]),
                    "of": len(vals)}
    return out


def seeds_table(rows: list) -> list:
    """report.md's lines for the rows settled at more than one seed (none when no row was)."""
    rows = [r for r in rows if r.get("settle_seeds")]
    if not rows:
        return []
    head = ["row", "settled phi by seed", "phi mean, sd", "pours' phi (floor)", "settled Z by seed", "Z mean, sd",
            "pours' Z (floor)", "mean Z - pours' (floors)", "within: phi / Z"]
    table = []
    for r in rows:
        ss, ref = r["settle_seeds"], r["reference"]
        cells = [r["row"]]
        for key in ("packing_fraction", "coordination"):
            by_seed = " / ".join(report.fmt(e["values"].get(key)) if e["status"] == "ok" else f"seed {e['seed']} failed"
                                 for e in ss["entries"])
            sm = ss["summary"].get(key)
            cells += [by_seed, f"{report.fmt(sm['mean'])}, {report.fmt(sm['sd'], 2)}" if sm else "-", _pm(ref, key)]
        z = ss["summary"].get("coordination")
        cells.append(f"{z['mean_error']:+.3f} ({z['mean_error_over_floor']:+.2g})"
                     if z and z["mean_error_over_floor"] is not None else "-")
        cells.append(" / ".join(f"{ss['summary'][k]['within']} of {ss['summary'][k]['of']}" if k in ss["summary"] else "-"
                                for k in ("packing_fraction", "coordination")))
        table.append(cells)
    return ["## `btr settle` across its seeds", "",
            "The same row settled at each seed (`btr settle SCENE --seed S`: another BTR deposit and another "
            "calibration pour), judged as the table above: how far one settle moves from seed to seed beside the "
            "pours' floor, and whether its mean lands on the pours'.", "",
            report.md_table(head, table), ""]


def threshold_in_floors(n_seeds: int) -> float:
    """The reach threshold in units of the floor: 2 sqrt(1 + 1/n)."""
    return 2.0 * math.sqrt(1.0 + 1.0 / n_seeds)


def cost_ratio(settle_cpu: float | None, pour_cpus: list) -> float | None:
    """settle's processor time / the mean processor time of the reference pours (None if either is missing)."""
    cpus = [c for c in pour_cpus if c is not None]
    if settle_cpu is None or not cpus or len(cpus) != len(pour_cpus):
        return None
    return float(settle_cpu) / float(np.mean(cpus))


def _pm(ref: dict, key: str) -> str:
    if not ref or key not in ref.get("mean", {}):
        return "-"
    return f"{report.fmt(ref['mean'][key])} +- {report.fmt(ref['floor'][key], 2)}"


def markdown(result: dict, fig_name: str | None) -> str:
    st = result["settings"]
    n = st["ref_seeds"]
    lines = ["# `btr settle` validation matrix", "",
             "Generated by `workflows/btrdem/studies/settle_matrix.py`; do not edit by hand. Command:", "",
             "```", result["command"], "```", "",
             f"Bed rows: {st['count']} grains, lateral size for a bed about {st['depth'] * 100:g} cm deep; heap rows: "
             f"{st['heap_count']} grains; engine {st['engine']}; reference: `btr pour` of each row's scene with seeds "
             f"{', '.join(str(s) for s in range(1, n + 1))}; `btr settle` with seed 1. A measure is reached when the "
             f"settled packing's error is within 2 s sqrt(1 + 1/n) = {threshold_in_floors(n):.3g} s of the pours' mean "
             "(s: the pours' seed-to-seed standard deviation, the floor; g(r): RMS distance of the curves). Cost ratio: "
             "settle's processor time (settle.json `cpu_seconds`, calibration included) / the mean reference pour's "
             "(pour.json `cpu_seconds`). Times are from a 2-core machine shared with other jobs.", ""]
    rows = result["rows"]
    pours = [["row", "grains", "engine", "pours' phi (mean +- floor)", "Z", "segregation", "heap angle [deg]",
              "g(r) floor (RMS)", "pour CPU [s] (mean)", "reused"]]
    for r in rows:
        ref = r.get("reference")
        if not ref:
            continue
        cpus = [c for c in ref["cpu_seconds"] if c is not None]
        pours.append([r["row"], r["count"], r["engine"], _pm(ref, "packing_fraction"), _pm(ref, "coordination"),
                      _pm(ref, "segregation"), _pm(ref, "angle_of_repose"),
                      report.fmt(ref["floor"].get("rdf")) if "rdf" in ref["floor"] else "-",
                      report.fmt(float(np.mean(cpus))) if cpus else "-",
                      f"{sum(ref['reused'])}/{len(ref['reused'])}"])
    lines += ["## Reference pours", ""]
    lines += [report.md_table(pours[0], pours[1:]) if len(pours) > 1 else "No row's pours finished yet.", ""]
    keys = [k for k in BED_MEASURES + HEAP_MEASURES if any(k in ((r.get("settle") or {}).get("judged") or {})
                                                           for r in rows)]
    table = [["row", "settle phi", "settle Z", "target phi (from)"] +
             [f"{SHORT[k]}: error / floor" for k in keys] + ["all within", "settle CPU [s]", "cost / pour"]]
    for r in rows:
        s = r.get("settle") or {}
        if not s.get("judged"):
            continue
        tgt = s.get("target_phi") or {}
        table.append([r["row"], report.fmt(s["values"].get("packing_fraction")),
                      report.fmt(s["values"].get("coordination")),
                      _target_cell(tgt)] +
                     [_judged_cell(s["judged"].get(k)) for k in keys] +
                     ["yes" if s["all_within"] else "no", report.fmt(s.get("cpu_seconds")), report.fmt(s.get("cost_ratio"))])
    lines += ["## `btr settle` against the pours", ""]
    lines += [report.md_table(table[0], table[1:]) if len(table) > 1 else "No row has a settled packing yet.", ""]
    lines += ["error / floor: the settled packing's error over the pours' seed-to-seed standard deviation; "
              f"(in) when within the reach threshold {threshold_in_floors(n):.3g}; target not reached rows say so.", ""]
    lines += seeds_table(rows)
    other = [[r["row"], r["label"], r["status"], r["reason"] or (r.get("settle") or {}).get("note", "")]
             for r in rows if r["status"] != "ok" or (r.get("settle") or {}).get("note")]
    if other:
        lines += ["## Rows that failed, were refused or are incomplete", "",
                  report.md_table(["row", "scene", "status", "reason"], other), ""]
    lines += ["Row scenes: [scenes/](scenes/).", ""]
    if fig_name:
        lines += [f"![error / floor per row]({fig_name})", ""]
    return "\n".join(lines)


def _target_cell(tgt: dict) -> str:
    """settle.json's chosen target_phi: its value and where it came from (a text, or btr settle's object with the
    source and the calibration's grains)."""
    if not tgt:
        return "-"
    src = tgt.get("from", "?")
    if isinstance(src, dict):
        src = src.get("source", "?") + (f", {src['grains']} grains" if "grains" in src else "")
    return f"{report.fmt(tgt.get('value'))} ({src})"


def _judged_cell(j) -> str:
    if j is None:
        return "-"
    if j["error_over_floor"] is None:
        return ("in" if j["within"] else "out") + " (floor 0)"
    return f"{j['error_over_floor']:.2g}" + (" (in)" if j["within"] else "")


def plot(path, result: dict) -> str:
    import matplotlib.pyplot as plt

    rows = [r for r in result["rows"] if r.get("reference") or (r.get("settle") or {}).get("judged")]
    n = result["settings"]["ref_seeds"]
    fig, (a0, a1) = plt.subplots(1, 2, figsize=(13, 4.6))
    names = [r["row"] for r in rows]
    x = np.arange(len(rows))
    for i, r in enumerate(rows):
        ref = r.get("reference") or {}
        if "packing_fraction" in ref.get("mean", {}):
            a0.errorbar([i], [ref["mean"]["packing_fraction"]], yerr=[ref["floor"]["packing_fraction"]], fmt="o",
                        color="tab:red", capsize=3, label="pours: mean +- floor" if i == 0 else None)
        s = r.get("settle") or {}
        if s.get("values", {}).get("packing_fraction") is not None:
            a0.plot([i], [s["values"]["packing_fraction"]], marker="*", ms=11, ls="none", color="tab:purple",
                    label="btr settle" if not any(a.get_label() == "btr settle" for a in a0.lines) else None)
    a0.set_ylabel("bulk packing fraction")
    a0.set_title("Packing fraction per row")
    markers = {"packing_fraction": "o", "coordination": "s", "rdf": "^", "segregation": "D", "angle_of_repose": "v"}
    width = 0.15
    plotted = False
    for k, key in enumerate(markers):
        pts = [(i, (r["settle"]["judged"].get(key) or {}).get("error_over_floor")) for i, r in enumerate(rows)
               if (r.get("settle") or {}).get("judged")]
        pts = [(i, max(v, 1e-2)) for i, v in pts if v is not None]
        if pts:
            plotted = True
            a1.plot([p[0] + (k - 2) * width for p in pts], [p[1] for p in pts], marker=markers[key], ls="none",
                    label=MEASURES[key])
    a1.axhline(threshold_in_floors(n), color="gray", ls="--", lw=1,
               label=f"reach threshold 2 sqrt(1 + 1/{n}) = {threshold_in_floors(n):.3g}")
    a1.axhline(1.0, color="gray", ls=":", lw=1, label="1 floor")
    a1.set_yscale("log")
    a1.set_ylabel("settle's error / pours' floor")
    a1.set_title("btr settle against the pours" + ("" if plotted else " (no settled row yet)"))
    for ax in (a0, a1):
        ax.set_xlim(-0.6, max(len(rows), 1) - 0.4)
        ax.set_xticks(x)
        ax.set_xticklabels(names, rotation=35, ha="right", fontsize=8)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return report.save_figure(fig, path)
