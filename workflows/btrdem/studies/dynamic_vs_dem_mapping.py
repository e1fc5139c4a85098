"""The drum mapping of `dynamic-vs-dem`: does some setting of dynamic BTR's own parameters make it agree with DEM?

Dynamic BTR's drum has two parameters of its own, the steps per revolution and the lift (a fraction of the drum
radius). The mapping part sweeps both on the study's drum cases (BTR only: seconds per run) and sets each
setting's measures (core index, radial index, t90, dynamic angle; mean over the seeds) against the DEM runs of
the same case, in DEM scatter units, per Froude number. The DEM side is read from the drum part's rows of the same
study (run it, or reuse its finished runs with --report-only); the sweep never reads them to choose a setting, it
only reports which setting comes closest."""
from __future__ import annotations

import numpy as np

from ..core import report
from ..core.io import atomic_write_text

KEYS = ["case", "steps_per_revolution", "lift_R", "seed", "status", "reason", "revolutions", "core_end",
        "segregation_end", "core_t90_rev", "dynamic_angle_deg", "cpu_per_rev"]
# The measures set against DEM: (row key, label).
MEASURES = [("core_end", "core index"), ("segregation_end", "radial index"), ("dynamic_angle_deg", "angle [deg]")]


def _mean(rows, key):
    v = [float(r[key]) for r in rows if r.get("status") == "ok" and r.get(key) is not None]
    v = [x for x in v if np.isfinite(x)]
    return (float(np.mean(v)), float(np.std(v, ddof=1)) if len(v) > 1 else None, len(v)) if v else (None, None, 0)


def summary(mapping_rows, drum_rows) -> list:
    """One row per (case, steps per revolution, lift): BTR means over the seeds and, per DEM Froude number, the
    error (BTR mean - DEM mean) / DEM sd of each measure; `worst` is the largest |error| over measures and speeds."""
    out = []
    for case in sorted({r["case"] for r in mapping_rows}):
        dem = [r for r in drum_rows if r["case"] == case and r["side"] != "btr"]
        froude = sorted({r["froude"] for r in dem})
        settings = sorted({(r["steps_per_revolution"], r["lift_R"]) for r in mapping_rows if r["case"] == case})
        for spr, lift in settings:
            runs = [r for r in mapping_rows if r["case"] == case and r["steps_per_revolution"] == spr
                    and r["lift_R"] == lift]
            row = {"case": case, "steps_per_revolution": spr, "lift_R": lift, "btr_n": _mean(runs, "core_end")[2]}
            errors = []
            for key, _ in MEASURES + [("core_t90_rev", "t90")]:
                row[key] = _mean(runs, key)[0]
            for fr in froude:
                at = [r for r in dem if r["froude"] == fr]
                for key, _ in MEASURES:
                    m, sd, _ = _mean(at, key)
                    err = (row[key] - m) / sd if row[key] is not None and m is not None and sd else None
                    row[f"{key}_error_fr{fr:g}"] = err
                    if err is not None:
                        errors.append(abs(err))
            row["worst"] = max(errors) if errors else None
            out.append(row)
    return out


def write_outputs(study) -> list:
    if not study.mapping_rows:
        return []
    summ = summary(study.mapping_rows, study.drum_rows)
    lines = [",".join(KEYS)] + [",".join("" if r.get(k) is None else str(r.get(k)).replace(",", ";") for k in KEYS)
                                for r in study.mapping_rows]
    atomic_write_text(study.out / "mapping_runs.csv", "\n".join(lines) + "\n")
    keys = sorted({k for r in summ for k in r}, key=lambda k: (k != "case", k))
    lines = [",".join(keys)] + [",".join("" if r.get(k) is None else str(r.get(k)) for k in keys) for r in summ]
    atomic_write_text(study.out / "mapping.csv", "\n".join(lines) + "\n")
    _figure(study, summ)
    return summ


def _figure(study, summ) -> None:
    import matplotlib.pyplot as plt
    cases = sorted({r["case"] for r in summ})
    fig, axes = plt.subplots(len(MEASURES), len(cases), figsize=(4.2 * len(cases), 2.8 * len(MEASURES)),
                             squeeze=False)
    for j, case in enumerate(cases):
        dem = [r for r in study.drum_rows if r["case"] == case and r["side"] != "btr"]
        for i, (key, label) in enumerate(MEASURES):
            ax = axes[i][j]
            for spr in sorted({r["steps_per_revolution"] for r in summ if r["case"] == case}):
                pts = sorted((r["lift_R"], r[key]) for r in summ if r["case"] == case
                             and r["steps_per_revolution"] == spr and r[key] is not None)
                if pts:
                    ax.plot(*zip(*pts), "-o", ms=3, lw=1, label=f"BTR {spr} steps/rev")
            for k, fr in enumerate(sorted({r["froude"] for r in dem})):
                m, sd, _ = _mean([r for r in dem if r["froude"] == fr], key)
                if m is not None:
                    ax.axhspan(m - (sd or 0.0), m + (sd or 0.0), color=f"C{7 + k}", alpha=0.3,
                               label=f"DEM Fr={fr:g} (mean +- sd)")
            ax.set_xscale("log")
            ax.set_xlabel("lift / R")
            ax.set_ylabel(label)
            ax.set_title(case, fontsize=9)
            if i == 0 and j == 0 and ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=6)
    fig.tight_layout()
    report.save_figure(fig, study.out / "mapping.png")


def report_section(summ) -> list:
    """The report's mapping section: every setting, then per case the one with the smallest worst error."""
    if not summ:
        return []
    f = report.fmt
    out = ["## Mapping: dynamic BTR's steps per revolution and lift against DEM", "",
           "BTR alone, swept over its own parameters on the drum cases (means over the seeds); error in DEM "
           "scatter units per Froude number, as above; worst: the largest |error| over the measures and speeds. "
           "The DEM rows are only compared with, never used to run BTR.", ""]
    fr_keys = sorted({k.split("_error_")[1] for r in summ for k in r if "_error_" in k})
    headers = ["case", "steps/rev", "lift/R", "seeds", "core", "radial", "t90 [rev]", "angle [deg]"]
    headers += [f"{m} err {fr}" for fr in fr_keys for _, m in MEASURES] + ["worst"]
    rows = []
    for r in summ:
        row = [r["case"], r["steps_per_revolution"], f(r["lift_R"]), r["btr_n"], f(r["core_end"]),
               f(r["segregation_end"]), f(r["core_t90_rev"]), f(r["dynamic_angle_deg"])]
        row += [f(r.get(f"{key}_error_{fr}")) for fr in fr_keys for key, _ in MEASURES] + [f(r["worst"])]
        rows.append(row)
    out += [report.md_table(headers, rows), "", "![mapping](mapping.png)", ""]
    for case in sorted({r["case"] for r in summ}):
        scored = [r for r in summ if r["case"] == case and r["worst"] is not None]
        if scored:
            b = min(scored, key=lambda r: r["worst"])
            out.append(f"- {case}: closest setting {b['steps_per_revolution']} steps per revolution, lift "
                       f"{f(b['lift_R'])} R, worst error {f(b['worst'])} DEM sd "
                       f"({'within' if b['worst'] <= 2.0 else 'outside'} 2 sd on every measure and speed).")
    return out + [""]
