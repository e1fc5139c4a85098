"""`stratification`: a two-species heap poured from a point source into a Hele-Shaw cell (seed 000 section 4,
Figs. 7-8; seed 003's cell and contact model), through BTR (the 2D analogue, a box of disks, and the 3D cell)
and through the LIGGGHTS reference pour of the same grains (btrdem.dem.pour, seed 003's Hooke model with its
Table I parameters per species, rolling friction off and on), each for several seeds.

Scene: inputs/stratification.toml (equal volumes of d = 1 and 2 mm spheres in a cell 4 mm wide). The 2D
case takes the same grains' radii as disks in a box as long as the cell, with N2D = n2d_fraction x N grains
(a heap about as many diameters high as the cell's). Rolling friction "on" is ROLLING on both species.

Every number comes from `btr measure` (btr/measures/stratification.cpp: layers parallel to the flank, stripe
wavelength and contrast against random mixtures of the same grains, top-toe segregation, angle per species;
definitions in docs/stratification/definitions.md). Cost: wall and processor time of the method's runs (BTR:
the deposit; DEM: the pour).

Every (method, seed) is a case (RunRecord.case): a failure, or a heap whose stratification cannot be
measured, is a row with its reason. report.md, stratification.csv, heaps.png, layers.png and run.json are
rewritten after every case."""
from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np

from ..core import btr_cli, report

from ..analysis import measures
from ..core.io import atomic_write_text, read_packing, read_scene_toml, write_scene_toml
from ..dem.pour import PourSettings, pour
from ..core.runner import REPO, RunRecord, find_btr

BASE = REPO / "inputs" / "stratification.toml"
ROLLING = 0.05  # inputs/bidisperse_heap.toml's rolling friction
METHODS = ("btr-2d", "btr-3d", "dem", "dem-rolling")
LABELS = {"btr-2d": "BTR 2D (disks)", "btr-3d": "BTR 3D cell", "dem": "DEM pour, rolling friction 0",
          "dem-rolling": f"DEM pour, rolling friction {ROLLING:g}"}
DEFAULT = {"n": 3000, "seeds": [1, 2, 3], "n2d_fraction": 1.0 / 3.0, "max_batches": 40, "pace": 1.0,
           "length_mm": 120.0}
TINY = {"n": 700, "seeds": [1], "n2d_fraction": 1.0 / 3.0, "max_batches": 8, "pace": 1.0, "length_mm": 60.0,
        "max_time": 0.3}


def scene_3d(base: dict, size: dict, n: int, seed: int, rolling: float) -> dict:
    s = copy.deepcopy(base)
    s["scene"]["name"] = f"strat3d_n{n}_seed{seed}" + ("_rolling" if rolling > 0 else "")
    s["scene"]["seed"] = int(seed)
    s["grains"]["count"] = int(n)
    length = size["length_mm"] * 1e-3
    s["container"]["size"] = [length]
    wall_gap = float(s["source"]["position"][0]) + 0.5 * float(base["container"]["size"][0])
    s["source"]["position"] = [-0.5 * length + wall_gap, 0.0]
    for m in [s["material"]] + [c["material"] for c in s["grains"]["component"]]:
        m["rolling_friction"] = float(rolling)
    if "max_time" in size:
        s["relax"]["max_time"] = size["max_time"]
    return s


def scene_2d(base: dict, size: dict, n: int, seed: int) -> dict:
    """The same grains as disks in a 2D box as long as the cell, fed at the same distance from its end wall."""
    s = scene_3d(base, size, n, seed, 0.0)
    s["scene"]["name"] = f"strat2d_n{n}_seed{seed}"
    s["scene"]["dimension"] = 2
    s["container"] = {"kind": "box", "size": s["container"]["size"], "height": s["container"]["height"]}
    s["source"]["position"] = [s["source"]["position"][0]]
    return s


FIELDS = ["method", "seed", "n", "status", "reason", "theta_deg", "theta_small_deg", "theta_large_deg",
          "wavelength_d", "peak_lag_d", "peak_autocorrelation", "peak_threshold", "contrast", "fluctuation_ratio",
          "sigma", "sigma_random", "layers", "small_fraction", "top_toe", "top_toe_noise", "small_top", "small_toe",
          "wall_s", "cpu_s", "stop", "note"]


def measure_case(csv_path) -> tuple[dict, dict]:
    """(row fields, the measures dict) from `btr measure`."""
    m = measures.measure(csv_path)
    h = m.get("heap") or {}
    st = m.get("stratification") or {}
    ang = {a["species"]: a["angle_of_repose_deg"] for a in st.get("angle_by_species", [])}
    row = {"theta_deg": h.get("angle_of_repose_deg"), "note": st.get("note", "")}
    if st.get("valid"):
        small, large = st["small_species"], st["large_species"]
        tt = st.get("top_toe") or {}
        row.update(theta_small_deg=ang.get(small), theta_large_deg=ang.get(large), wavelength_d=st["wavelength_d"],
                   peak_lag_d=st["peak_lag_d"], peak_autocorrelation=st["peak_autocorrelation"],
                   peak_threshold=st["peak_threshold"], contrast=st["contrast"],
                   fluctuation_ratio=st["fluctuation_ratio"], sigma=st["sigma"], sigma_random=st["sigma_random"],
                   layers=len(st["layers"]["depth_d"]), small_fraction=st["small_fraction"],
                   top_toe=tt.get("index"), top_toe_noise=tt.get("noise"), small_top=tt.get("small_fraction_top"),
                   small_toe=tt.get("small_fraction_toe"))
    return row, m


def _mean_std(values):
    v = [float(x) for x in values if x is not None]
    if not v:
        return None, None, 0
    return float(np.mean(v)), (float(np.std(v, ddof=1)) if len(v) > 1 else None), len(v)


def _pm(values, digits=3):
    m, s, k = _mean_std(values)
    if m is None:
        return "-"
    return f"{m:.{digits}g}" + (f" +- {s:.2g}" if s is not None else "") + (f" ({k})" if k else "")


def summary_table(rows: list) -> list:
    """Per method: the mean +- sample std over the seeds that gave a number (count in brackets)."""
    md = ["| method | rows ok / all | theta [deg] | theta small | theta large | seeds with a wavelength | "
          "wavelength [d] | contrast | fluctuation / random | top-toe index | top-toe / noise | wall [s] | CPU [s] |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for method in METHODS:
        sel = [r for r in rows if r["method"] == method]
        if not sel:
            continue
        ok = [r for r in sel if r["status"] == "ok"]
        waves = [r for r in ok if r.get("wavelength_d") is not None]
        ratio = [r["top_toe"] / r["top_toe_noise"] for r in ok
                 if r.get("top_toe") is not None and r.get("top_toe_noise")]
        md.append(f"| {LABELS[method]} | {len(ok)} / {len(sel)} | {_pm([r.get('theta_deg') for r in sel])} | "
                  f"{_pm([r.get('theta_small_deg') for r in sel])} | {_pm([r.get('theta_large_deg') for r in sel])} | "
                  f"{len(waves)} / {len(ok)} | {_pm([r['wavelength_d'] for r in waves])} | "
                  f"{_pm([r.get('contrast') for r in ok])} | {_pm([r.get('fluctuation_ratio') for r in ok])} | "
                  f"{_pm([r.get('top_toe') for r in ok])} | {_pm(ratio)} | {_pm([r.get('wall_s') for r in sel])} | "
                  f"{_pm([r.get('cpu_s') for r in sel])} |")
    return md


def against_dem(rows: list) -> list:
    """Each BTR method's seed means minus the DEM pours' (rolling friction off and on)."""
    md = ["| method | reference | theta - ref [deg] | theta small - ref | theta large - ref | contrast - ref | "
          "top-toe - ref | CPU / ref CPU |", "|---|---|---|---|---|---|---|---|"]
    key = ("theta_deg", "theta_small_deg", "theta_large_deg", "contrast", "top_toe")
    for ref in ("dem", "dem-rolling"):
        rr = [r for r in rows if r["method"] == ref and r["status"] == "ok"]
        if not rr:
            continue
        for method in ("btr-2d", "btr-3d"):
            mm = [r for r in rows if r["method"] == method and r["status"] == "ok"]
            if not mm:
                continue
            cells = []
            for k in key:
                a, _, _ = _mean_std([r.get(k) for r in mm])
                b, _, _ = _mean_std([r.get(k) for r in rr])
                cells.append("-" if a is None or b is None else f"{a - b:+.3g}")
            a, _, _ = _mean_std([r.get("cpu_s") for r in mm])
            b, _, _ = _mean_std([r.get("cpu_s") for r in rr])
            cells.append("-" if not a or not b else f"{a / b:.3g}")
            md.append(f"| {LABELS[method]} | {LABELS[ref]} | " + " | ".join(cells) + " |")
    return md


def _write_tables(out: Path, rows: list, settings: dict, command: str):
    lines = [",".join(FIELDS)]
    for r in rows:
        lines.append(",".join(str("" if r.get(k) is None else r.get(k)).replace(",", ";") for k in FIELDS))
    atomic_write_text(out / "stratification.csv", "\n".join(lines) + "\n")
    md = ["# Stratification of a two-species heap: BTR beside DEM in a Hele-Shaw cell", "",
          f"Command: `{command}`", "", f"Settings: {settings}", "",
          "Measures from `btr measure` (btr/measures/stratification.cpp; definitions in docs/stratification/definitions.md): "
          "theta = the heap's flank angle; theta small / large = the flank angle of each species' own skyline; "
          "wavelength = stripe period across layers parallel to the flank, in mean diameters (- = not significant "
          "against 200 random mixtures of the same grains at the 99 % level); contrast = the layers' excess "
          "fluctuation of the small-species fraction over random mixtures, relative to pure layers (0 = no more "
          "than random); top-toe = small fraction in the top third minus the toe third (> 0: small grains at the "
          "top), noise = its std over the random mixtures. Cost: wall and processor (CPU) time of the method's "
          "runs on 2 cores shared with other jobs.", "",
          "## Per method (mean +- sample std over seeds; count of seeds in brackets)", ""]
    md += summary_table(rows)
    md += ["", "## BTR against the DEM pours (seed means)", ""]
    md += against_dem(rows)
    md += ["", "## Every case", "",
           "| method | seed | N | status | theta | theta small | theta large | wavelength [d] | peak lag [d] | "
           "peak A / threshold | contrast | fluct. / random | layers | top-toe (noise) | wall [s] | CPU [s] | stop | "
           "reason / note |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    f = report.fmt
    for r in rows:
        peak = (f"{f(r.get('peak_autocorrelation'), 3)} / {f(r.get('peak_threshold'), 3)}"
                if r.get("peak_autocorrelation") is not None else "-")
        tt = f"{f(r.get('top_toe'), 3)} ({f(r.get('top_toe_noise'), 2)})" if r.get("top_toe") is not None else "-"
        why = r.get("reason") or r.get("note") or ""
        md.append(f"| {LABELS.get(r['method'], r['method'])} | {r['seed']} | {r.get('n', '')} | {r['status']} | "
                  f"{f(r.get('theta_deg'), 3)} | {f(r.get('theta_small_deg'), 3)} | {f(r.get('theta_large_deg'), 3)} | "
                  f"{f(r.get('wavelength_d'), 3) if r.get('wavelength_d') is not None else '-'} | "
                  f"{f(r.get('peak_lag_d'), 3) if r.get('peak_lag_d') is not None else '-'} | {peak} | "
                  f"{f(r.get('contrast'), 3)} | {f(r.get('fluctuation_ratio'), 3)} | {r.get('layers', '')} | {tt} | "
                  f"{f(r.get('wall_s'), 3)} | {f(r.get('cpu_s'), 3)} | {r.get('stop', '')} | "
                  f"{str(why).splitlines()[0] if why else ''} |")
    md += ["", "Figures: heaps.png (each heap coloured by species, small = orange, with the fitted flank line), "
               "layers.png (small-species fraction per layer and its autocorrelation)", ""]
    atomic_write_text(out / "report.md", "\n".join(md) + "\n")


def _draw_heap(ax, p, m: dict, window=None):
    """Grains of packing p as disks to scale (3D: projected on x-z, the front plate's drawn last), small
    species orange, large blue; the fitted flank line(s) dashed. x is measured from the source axis, in mm.
    window: (x0, x1, z0, z1) in mm, or None for the whole heap."""
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle
    x0 = float(m["heap"]["axis"][0])
    st = m.get("stratification") or {}
    sizes = np.unique(p.radius)
    small = (p.species == st["small_species"]) if st.get("valid") else (p.radius <= sizes[0] * 1.05)
    x, z = (p.pos[:, 0] - x0) * 1e3, p.pos[:, 2] * 1e3
    keep = np.ones(len(p), bool)
    if window is not None:
        keep = (x > window[0] - 3) & (x < window[1] + 3) & (z > window[2] - 3) & (z < window[3] + 3)
    idx = np.nonzero(keep)[0]
    order = idx[np.argsort(-p.pos[idx, 1])] if p.dimension == 3 else idx
    patches = [Circle((x[k], z[k]), p.radius[k] * 1e3) for k in order]
    ax.add_collection(PatchCollection(patches, facecolors=np.where(small[order], "#e6550d", "#3182bd"),
                                      edgecolors="none", linewidths=0))
    for side, line in (m["heap"].get("flank_lines") or {}).items():
        sign = -1.0 if side == "left" else 1.0
        t = math.tan(math.radians(line["angle_deg"]))
        u = np.array([0.0, line["intercept"] / t])
        ax.plot(sign * u * 1e3, (line["intercept"] - u * t) * 1e3, "k--", lw=0.7)
    ax.set_aspect("equal")
    if window is None:
        ax.set_xlim(np.min(x) - 2, np.max(x) + 2)
        ax.set_ylim(0, np.max(z + p.radius * 1e3) + 2)
    else:
        ax.set_xlim(window[0], window[1])
        ax.set_ylim(window[2], window[3])


def _heaps_figure(out: Path, cases: dict, seeds: list):
    """Every heap, rows = methods, columns = seeds."""
    if not cases:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    methods = [m for m in METHODS if any(k[0] == m for k in cases)]
    fig, axes = plt.subplots(len(methods), len(seeds), figsize=(4.2 * len(seeds), 2.3 * len(methods)),
                             squeeze=False)
    for i, method in enumerate(methods):
        for j, seed in enumerate(seeds):
            ax = axes[i][j]
            ax.tick_params(labelsize=6)
            c = cases.get((method, seed))
            if c is None:
                ax.set_title(f"{LABELS[method]}, seed {seed}: no heap", fontsize=7)
                continue
            _draw_heap(ax, c["packing"], c["measures"])
            r = c["row"]
            wl = r.get("wavelength_d")
            ax.set_title(f"{LABELS[method]}, seed {seed}: theta {report.fmt(r.get('theta_deg'), 3)} deg, "
                         f"wavelength {report.fmt(wl, 3) if wl is not None else '-'} d, contrast "
                         f"{report.fmt(r.get('contrast'), 2)}", fontsize=6)
    fig.tight_layout()
    report.save_figure(fig, out / "heaps.png")


def closeup(packing_csv, out_png, window_mm=None, title: str = ""):
    """A figure of one heap coloured by species (as heaps.png draws it), whole or a window (x0, x1, z0, z1)
    in mm from the source axis, with its stratification numbers from `btr measure` in the title. For heaps
    measured by hand (docs/stratification/README.md), e.g.
      cd workflows && /usr/bin/python3 -c "from btrdem.studies.stratification import closeup;
          closeup('../out/bh1e5/btr.csv', '../docs/stratification/btr2d_1e5_closeup.png', (60, 140, 100, 160))"
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    p = read_packing(packing_csv)
    m = measures.measure(packing_csv)
    st = m.get("stratification") or {}
    fig, ax = plt.subplots(figsize=(7, 7 * ((window_mm[3] - window_mm[2]) / (window_mm[1] - window_mm[0]))
                                    if window_mm else 4))
    _draw_heap(ax, p, m, window_mm)
    wl = st.get("wavelength_d")
    ax.set_title((title + ": " if title else "") + f"N = {len(p)}, theta {report.fmt(m['heap'].get('angle_of_repose_deg'), 3)}"
                 f" deg, wavelength {report.fmt(wl, 3) if wl is not None else '-'} d, contrast "
                 f"{report.fmt(st.get('contrast'), 2)}, top-toe {report.fmt((st.get('top_toe') or {}).get('index'), 2)}",
                 fontsize=7)
    ax.set_xlabel("x - source x [mm]", fontsize=7)
    ax.set_ylabel("z [mm]", fontsize=7)
    ax.tick_params(labelsize=6)
    fig.tight_layout()
    report.save_figure(fig, out_png)
    return m


def _layers_figure(out: Path, cases: dict):
    if not cases:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    methods = [m for m in METHODS if any(k[0] == m for k in cases)]
    fig, axes = plt.subplots(2, len(methods), figsize=(3.4 * len(methods), 5.2), squeeze=False)
    for j, method in enumerate(methods):
        for (meth, seed), c in sorted(cases.items()):
            st = c["measures"].get("stratification") or {}
            if meth != method or not st.get("valid"):
                continue
            lay = st["layers"]
            axes[0][j].plot(lay["depth_d"], lay["small_fraction"], label=f"seed {seed}", lw=0.9)
            lag = np.arange(len(st["autocorrelation"])) * st["layer_d"]
            axes[1][j].plot(lag, st["autocorrelation"], label=f"seed {seed}", lw=0.9)
        axes[0][j].set_title(LABELS[method], fontsize=8)
        axes[0][j].set_xlabel("depth below the flank [mean d]", fontsize=7)
        axes[0][j].set_ylabel("small-species volume fraction", fontsize=7)
        axes[1][j].set_xlabel("lag [mean d]", fontsize=7)
        axes[1][j].set_ylabel("autocorrelation", fontsize=7)
        axes[1][j].axhline(0.0, color="k", lw=0.5)
        for ax in (axes[0][j], axes[1][j]):
            ax.tick_params(labelsize=7)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=6)
    fig.tight_layout()
    report.save_figure(fig, out / "layers.png")


def run_stratification(outdir, tiny: bool = False, seeds=None, n: int | None = None, methods=METHODS,
                       progress=print, pour_time_limit: float = 7200.0) -> dict:
    size = dict(TINY if tiny else DEFAULT)
    if seeds:
        size["seeds"] = [int(s) for s in seeds]
    if n:
        size["n"] = int(n)
    out = Path(outdir or "out/stratification").resolve()
    btr = find_btr()
    base = read_scene_toml(BASE)
    n2d = max(10, int(round(size["n"] * size["n2d_fraction"])))
    settings = {"mode": "tiny" if tiny else "default", "rolling_friction_on": ROLLING, "n2d": n2d,
                "methods": list(methods), **size}
    rec = RunRecord(out, "stratification", inputs=[str(BASE)], btr=btr, progress=progress, settings=settings)
    command = " ".join(Path(a).name if k == 0 else str(a) for k, a in enumerate(rec.data["command"][1:]))
    rows, cases = [], {}

    def on_row(_rows):
        _write_tables(out, rows, settings, "/usr/bin/python3 workflows/" + command)
        _heaps_figure(out, cases, size["seeds"])
        _layers_figure(out, cases)

    for seed in size["seeds"]:
        for method in methods:
            case_dir = out / "cases" / f"{method}_seed{seed}"
            case_dir.mkdir(parents=True, exist_ok=True)
            row = {"method": method, "seed": seed, "n": n2d if method == "btr-2d" else size["n"]}
            with rec.case(f"{LABELS[method]} seed {seed}", rows, row, on_row):
                if method == "btr-2d":
                    scene = scene_2d(base, size, n2d, seed)
                else:
                    scene = scene_3d(base, size, size["n"], seed, ROLLING if method == "dem-rolling" else 0.0)
                write_scene_toml(case_dir / "scene.toml", scene)
                dep = btr_cli.deposit(btr, str(case_dir / "scene.toml"), case_dir / "btr", name="btr",
                                      progress=progress)
                csv_path, wall, cpu, stop = dep["csv"], dep["wall_seconds"], dep["cpu_seconds"], ""
                if method.startswith("dem"):
                    # the pour takes the grains (radii, species, order) of the BTR deposit, not its positions
                    s = pour(read_packing(csv_path), case_dir / "dem",
                             PourSettings(pace=size["pace"], max_batches=size["max_batches"], seed=seed,
                                          label=f"pour {method} seed {seed}", wall_time_limit=pour_time_limit),
                             progress=progress)
                    csv_path, wall, cpu, stop = s["packing"], s["wall_seconds"], s["cpu_seconds"], s["stop_reason"]
                row.update(wall_s=wall, cpu_s=cpu, stop=stop)
                fields, m = measure_case(csv_path)
                row.update(fields)
                cases[(method, seed)] = {"packing": read_packing(csv_path), "measures": m, "row": row}
                if m.get("heap", {}).get("angle_of_repose_deg") is None:
                    raise RuntimeError(f"heap angle not measured: {m['heap'].get('note', '')}")
                if not (m.get("stratification") or {}).get("valid"):
                    raise RuntimeError(f"stratification not measured: {m['stratification'].get('note', '')}")
    failed = sum(r["status"] != "ok" for r in rows)
    rec.finish({"rows": len(rows), "failed": failed})
    progress(f"stratification: {len(rows)} rows ({failed} failed); report {out / 'report.md'}")
    return {"rows": rows, "out": str(out)}
