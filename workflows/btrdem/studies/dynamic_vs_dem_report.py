"""Tables, figures and report.md of `dynamic-vs-dem` (dynamic_vs_dem.py), rewritten after every run.

The comparison unit is DEM's seed-to-seed scatter: for each measure, (BTR mean - DEM mean) / DEM standard
deviation over the DEM seeds. BTR "agrees" where that is within 2 (and the DEM scatter was measured: 2 seeds
or more)."""
from __future__ import annotations

import numpy as np

from ..core import report
from ..core.io import atomic_write_text
from . import dynamic_vs_dem_mapping as out_mapping

DRUM_KEYS = ["case", "side", "froude", "seed", "dimension", "grains", "status", "reason", "revolutions",
             "segregation_end", "core_end", "core_t90_rev", "dynamic_angle_deg", "cpu_per_rev", "cpu_seconds"]
BRAZIL_KEYS = ["case", "phi", "side", "seed", "status", "reason", "cycles", "z0_d", "z_end_d", "rise_d_per_cycle",
               "cpu_per_cycle"]
COST_KEYS = ["case", "side", "grains", "froude", "revolutions_run", "status", "reason", "cpu_per_rev"]
MEASURES = [("core_end", "core index (last rev)"), ("segregation_end", "radial index (last rev)"),
            ("core_t90_rev", "rev to 90 % of core index"), ("dynamic_angle_deg", "dynamic angle [deg]"),
            ("cpu_per_rev", "CPU s per rev")]
AGREE = 2.0


def plan_summary(plan: dict) -> str:
    """The plan in one sentence: the drums (dimension, fills, Froude numbers, revolutions, DEM seeds), the Brazil
    nut, the cost scene and the mapping's settings."""
    drums = "; ".join(f"{p['dim']}D {p['fill_name']} fill {p['fill']:g} at Fr {', '.join(f'{f:g}' for f in p['froude'])}, "
                      f"{p['revolutions']:g} rev, {p['dem_seeds']} DEM seed(s)" for p in plan["drum"])
    b = plan["brazil"]
    brazil = (f"Brazil nut Phi {', '.join(f'{x:g}' for x in b['phis'])}, {b['count']} grains, {b['taps']} taps at "
              f"Gamma {b['gamma']:g}, {b['dem_seeds']} DEM seed(s)")
    m = plan.get("mapping", {})
    mapping = (f"; mapping: {', '.join(str(x) for x in m['steps'])} steps per revolution, lifts "
               f"{', '.join(f'{x:g}' for x in m['lifts'])} R" if m else "")
    return f"drums: {drums}; {brazil}; cost at {plan['cost_grains']} grains{mapping}"


def _csv(rows, keys) -> str:
    lines = [",".join(keys)]
    for r in rows:
        lines.append(",".join("" if r.get(k) is None else str(r.get(k)).replace(",", ";") for k in keys))
    return "\n".join(lines) + "\n"


def _values(rows, key):
    v = [r.get(key) for r in rows if r.get("status") == "ok" and r.get(key) is not None]
    return np.array([float(x) for x in v if np.isfinite(float(x))])


def comparison(drum_rows) -> list:
    """One row per (case, DEM Froude number, measure): BTR mean, DEM mean +- sd, error in DEM sd units."""
    out = []
    cases = sorted({r["case"] for r in drum_rows})
    for case in cases:
        btr = [r for r in drum_rows if r["case"] == case and r["side"] == "btr"]
        dem_fr = sorted({r["froude"] for r in drum_rows if r["case"] == case and r["side"] != "btr"})
        for fr in dem_fr:
            dem = [r for r in drum_rows if r["case"] == case and r["side"] != "btr" and r["froude"] == fr]
            for key, label in MEASURES:
                b, d = _values(btr, key), _values(dem, key)
                row = {"case": case, "froude": fr, "measure": label, "btr_mean": float(b.mean()) if len(b) else None,
                       "btr_n": len(b), "dem_mean": float(d.mean()) if len(d) else None,
                       "dem_sd": float(d.std(ddof=1)) if len(d) > 1 else None, "dem_n": len(d)}
                if key == "cpu_per_rev":
                    row["error_sd"] = None
                    row["ratio"] = (row["dem_mean"] / row["btr_mean"]) if len(b) and len(d) and b.mean() > 0 else None
                else:
                    ok = row["btr_mean"] is not None and row["dem_mean"] is not None and row["dem_sd"]
                    row["error_sd"] = (row["btr_mean"] - row["dem_mean"]) / row["dem_sd"] if ok else None
                    row["ratio"] = None
                out.append(row)
    return out


def write_outputs(study) -> None:
    out = study.out
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "drum_runs.csv", _csv(study.drum_rows, DRUM_KEYS))
    atomic_write_text(out / "brazil_runs.csv", _csv(study.brazil_rows, BRAZIL_KEYS))
    atomic_write_text(out / "cost.csv", _csv(study.cost_rows, COST_KEYS))
    comp = comparison(study.drum_rows)
    atomic_write_text(out / "drum_vs_dem.csv", _csv(comp, ["case", "froude", "measure", "btr_mean", "btr_n",
                                                           "dem_mean", "dem_sd", "dem_n", "error_sd", "ratio"]))
    _figures(study)
    text = _report(study, comp)
    mapping = out_mapping.write_outputs(study)
    atomic_write_text(out / "report.md", text + "\n" + "\n".join(out_mapping.report_section(mapping)))


def _figures(study) -> None:
    import matplotlib.pyplot as plt
    cases = sorted({r["case"] for r in study.drum_rows})
    if cases:
        fig, axes = plt.subplots(1, len(cases), figsize=(5 * len(cases), 3.8), squeeze=False)
        for case, ax in zip(cases, axes.flat):
            for r in study.drum_rows:
                tag = f"{case}_{r['side']}" + (f"_fr{r['froude']:g}" if r["froude"] is not None else "") + \
                      f"_s{r['seed']}"
                if r["case"] != case or tag not in study.series:
                    continue
                rev, core, _ = study.series[tag]
                label = "BTR" if r["side"] == "btr" else f"{r['side']} Fr={r['froude']:g}"
                style = "-" if r["side"] == "btr" else "--"
                ax.plot(rev, core, style, label=f"{label} s{r['seed']}", lw=1)
            ax.set_title(case, fontsize=9)
            ax.set_xlabel("revolutions")
            ax.set_ylabel("core index (large - small) / R")
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=6)
        fig.tight_layout()
        report.save_figure(fig, study.out / "segregation_vs_dem.png")
    phis = sorted({r["phi"] for r in study.brazil_rows})
    if phis:
        fig, axes = plt.subplots(1, len(phis), figsize=(4 * len(phis), 3.4), squeeze=False)
        for phi, ax in zip(phis, axes.flat):
            for r in study.brazil_rows:
                tag = f"phi{phi:g}_{r['side']}_s{r['seed']}"
                if r["phi"] != phi or tag not in study.series:
                    continue
                x, z, _ = study.series[tag]
                ax.plot(x, z, "-o" if r["side"] == "btr" else "--s", ms=3,
                        label=("BTR cycles" if r["side"] == "btr" else f"{r['side']} taps") + f" s{r['seed']}")
            ax.set_title(f"Phi = {phi:g}", fontsize=9)
            ax.set_xlabel("cycle (BTR) / tap (DEM)")
            ax.set_ylabel("intruder centre height [d]")
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=6)
        fig.tight_layout()
        report.save_figure(fig, study.out / "intruder_vs_dem.png")


def _report(study, comp) -> str:
    f = report.fmt
    out = ["# Dynamic BTR against DEM", "",
           "Generated by `workflows/btrdem/studies/dynamic_vs_dem.py`; do not edit by hand. The same scene (grains, "
           "fill, seed) runs through dynamic BTR (`btr drum`, `btr shake`) and through DEM (`btr drum --engine`, "
           "`btr shake --engine`); both write the same table, measured by the same C++ functions. Settings: "
           f"engine {study.engine}, seeds {', '.join(str(s) for s in study.seeds)}; {plan_summary(study.plan)} "
           "(the whole plan in run.json).", "",
           "## Drum: BTR against DEM, in DEM scatter units", "",
           f"error = (BTR mean - DEM mean) / DEM seed-to-seed standard deviation; BTR agrees where |error| <= "
           f"{AGREE:g}. Core index: (mean distance of the large grains from the fill's centre of mass - that of "
           "the small ones) / R; radial index: the same from the drum's axis; t90: revolutions to 90 % of the final "
           "core index; dynamic angle: free-surface slope over |x| <= 0.6 R, mean over the last revolution. CPU "
           "ratio: DEM processor seconds per revolution over BTR's.", ""]
    rows = []
    for c in comp:
        verdict = ""
        if c["error_sd"] is not None:
            verdict = "agrees" if abs(c["error_sd"]) <= AGREE else "differs"
        rows.append([c["case"], f(c["froude"]), c["measure"], f(c["btr_mean"]), f(c["dem_mean"]), f(c["dem_sd"]),
                     c["dem_n"], f(c["error_sd"]) if c["ratio"] is None else f"DEM/BTR = {f(c['ratio'])}", verdict])
    out.append(report.md_table(["case", "Froude", "measure", "BTR", "DEM mean", "DEM sd", "DEM seeds",
                                "error [DEM sd]", ""], rows) if rows else "(no drum run finished yet)")
    out += ["", "![core index against revolutions](segregation_vs_dem.png)", "", "### Every drum run", ""]
    out.append(report.md_table(
        ["case", "side", "Froude", "seed", "grains", "status", "revolutions", "core index", "radial index", "t90 [rev]",
         "angle [deg]", "CPU s / rev", "reason"],
        [[r["case"], r["side"], f(r.get("froude")), r["seed"], r.get("grains"), r["status"], f(r.get("revolutions")),
          f(r.get("core_end")), f(r.get("segregation_end")), f(r.get("core_t90_rev")), f(r.get("dynamic_angle_deg")),
          f(r.get("cpu_per_rev")), r.get("reason", "")] for r in study.drum_rows]) if study.drum_rows else "(none)")
    out += ["", "## Cost per revolution at the study's largest drum", ""]
    out.append(report.md_table(["case", "side", "grains", "Froude", "revolutions run", "status", "CPU s / rev",
                                "reason"],
                               [[r["case"], r["side"], r["grains"], f(r.get("froude")), f(r.get("revolutions_run")),
                                 r["status"], f(r.get("cpu_per_rev")), r.get("reason", "")]
                                for r in study.cost_rows]) if study.cost_rows else "(not run)")
    btr = [r["cpu_per_rev"] for r in study.cost_rows if r["side"] == "btr" and r.get("cpu_per_rev")]
    dem = [r["cpu_per_rev"] for r in study.cost_rows if r["side"] != "btr" and r.get("cpu_per_rev")]
    if btr and dem:
        out += ["", f"DEM / BTR processor time per revolution: {f(dem[0] / btr[0])}x."]
    out += ["", "## Brazil nut: intruder height, BTR cycles against DEM taps", ""]
    out.append(report.md_table(["Phi", "side", "seed", "status", "cycles / taps", "z start [d]", "z end [d]",
                                "rise [d per cycle]", "CPU s per cycle (fill included)", "reason"],
                               [[f(r["phi"]), r["side"], r["seed"], r["status"], r.get("cycles"), f(r.get("z0_d")),
                                 f(r.get("z_end_d")), f(r.get("rise_d_per_cycle")), f(r.get("cpu_per_cycle")),
                                 r.get("reason", "")] for r in study.brazil_rows]) if study.brazil_rows else "(none)")
    out += ["", "![intruder height](intruder_vs_dem.png)", ""]
    return "\n".join(out)
