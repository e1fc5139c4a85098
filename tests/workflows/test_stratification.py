"""stratification on tiny settings (700 grains in the 3D cell, 233 disks in 2D, one seed; LIGGGHTS pours for
real with rolling friction off and on), a failed case is a row with its reason, seed 003's Table I per
species worked out by hand against the pour's input, and the report's tables on rows of known values."""
import csv
import json
import re
import subprocess
import sys

import numpy as np

from btrdem.studies import stratification


def _matrix(script: str, name: str) -> list:
    line = next(x for x in script.splitlines() if re.search(rf"property/global {name} peratomtypepair", x))
    return [float(v) for v in line.split("peratomtypepair")[1].split()[1:]]


def test_stratification_tiny(tmp_path, source_dir, btr_binary):
    out = tmp_path / "st"
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "stratification", "--tiny",
                        "-o", str(out)], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    rows = list(csv.DictReader(open(out / "stratification.csv")))
    assert [r["method"] for r in rows] == list(stratification.METHODS)
    theta = {}
    for r in rows:
        assert r["status"] == "ok", r
        theta[r["method"]] = float(r["theta_deg"])
        assert 0 <= float(r["contrast"]) <= 1.5 and float(r["fluctuation_ratio"]) > 0, r
        assert int(r["layers"]) >= 8, r
        # top and toe fractions are volume fractions of the small species; the index is their difference
        assert abs(float(r["top_toe"]) - (float(r["small_top"]) - float(r["small_toe"]))) < 1e-9, r
        assert 0 <= float(r["small_top"]) <= 1 and 0 <= float(r["small_toe"]) <= 1
        assert float(r["cpu_s"]) >= 0 and float(r["wall_s"]) > 0
    assert [r["n"] for r in rows] == ["233", "700", "700", "700"]
    # BTR has no inertia: its heaps are the steeper ones; the pours stopped by a rule of the pour
    assert min(theta["btr-2d"], theta["btr-3d"]) > max(theta["dem"], theta["dem-rolling"]) + 10, theta
    assert {r["stop"] for r in rows if r["method"].startswith("dem")} <= {"kinetic-energy", "max-time"}
    # the row's numbers are btr measure's on the case's packing
    m = json.loads(subprocess.run([btr_binary, "measure", str(out / "cases" / "dem_seed1" / "dem" / "poured.csv")],
                                  capture_output=True, text=True, check=True).stdout)
    dem = next(r for r in rows if r["method"] == "dem")
    assert float(dem["contrast"]) == m["stratification"]["contrast"]
    assert float(dem["theta_deg"]) == m["heap"]["angle_of_repose_deg"]
    # seed 003 Table I per species, by hand: m = 2400 pi/6 d^3, kn = 2e3 m g / d, t0 = sqrt(d / g)
    # d = 1 mm: m = 1.2566e-6 kg, kn = 24.6552 N/m, gamma_n = 50 / 0.0100964 s = 4952.27 1/s
    # d = 2 mm: m = 1.00531e-5 kg, kn = 98.6209 N/m, gamma_n = 50 / 0.0142785 s = 3501.79 1/s
    kn_s, kn_l, gn_s, gn_l = 24.6552, 98.6209, 4952.27, 3501.79
    for method in ("dem", "dem-rolling"):
        script = (out / "cases" / f"{method}_seed1" / "dem" / "in.btr").read_text()
        assert "model hooke/stiffness tangential history" in script
        # types 1 = small, 2 = large, 3 = walls (a grain-wall pair takes the grain's value)
        assert np.allclose(_matrix(script, "kn"), [kn_s, (kn_s + kn_l) / 2, kn_s, (kn_s + kn_l) / 2, kn_l, kn_l,
                                                   kn_s, kn_l, kn_s], rtol=1e-5)
        assert np.allclose(_matrix(script, "gamman"), [gn_s, (gn_s + gn_l) / 2, gn_s, (gn_s + gn_l) / 2, gn_l, gn_l,
                                                       gn_s, gn_l, gn_s], rtol=1e-5)
        assert np.allclose(_matrix(script, "kt"), list(np.array(_matrix(script, "kn")) * 2 / 7), rtol=1e-5)
        rolling = "rolling_friction epsd2" in script
        assert rolling == (method == "dem-rolling"), method
        if rolling:
            assert np.allclose(_matrix(script, "coefficientRollingFriction"), [stratification.ROLLING] * 9)
    assert (out / "heaps.png").stat().st_size > 0 and (out / "layers.png").stat().st_size > 0
    report = (out / "report.md").read_text()
    for label in stratification.LABELS.values():
        assert report.count(f"| {label} | 1 | ") == 1, label
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "ok" and len(run["steps"]) == 4


def test_a_failed_case_is_a_row_with_its_reason(tmp_path, btr_binary):
    out = tmp_path / "st"
    res = stratification.run_stratification(out, tiny=True, methods=("dem", "btr-3d"), pour_time_limit=0.01,
                                            progress=lambda *_: None)
    rows = {r["method"]: r for r in res["rows"]}
    assert rows["dem"]["status"] == "fail" and "time limit" in rows["dem"]["reason"], rows["dem"]
    assert rows["btr-3d"]["status"] == "ok" and rows["btr-3d"]["theta_deg"] > 30
    table = list(csv.DictReader(open(out / "stratification.csv")))
    assert [(r["method"], r["status"]) for r in table] == [("dem", "fail"), ("btr-3d", "ok")]
    assert "time limit" in (out / "report.md").read_text()


def test_summary_tables_on_known_rows():
    rows = [{"method": "dem", "seed": s, "status": "ok", "theta_deg": t, "contrast": 0.2, "top_toe": 0.1,
             "top_toe_noise": 0.05, "wavelength_d": w, "cpu_s": 10.0, "wall_s": 12.0}
            for s, t, w in ((1, 20.0, 6.0), (2, 22.0, None), (3, 24.0, 8.0))]
    rows += [{"method": "btr-3d", "seed": 1, "status": "ok", "theta_deg": 60.0, "contrast": 0.0, "top_toe": 0.3,
              "top_toe_noise": 0.1, "wavelength_d": None, "cpu_s": 0.1, "wall_s": 0.2},
             {"method": "btr-3d", "seed": 2, "status": "fail", "reason": "x"}]
    md = "\n".join(stratification.summary_table(rows))
    # DEM: theta 22 +- 2 over 3 seeds; wavelength in 2 of 3 seeds, 7 +- 1.4; top-toe / noise = 2
    assert "| DEM pour, rolling friction 0 | 3 / 3 | 22 +- 2 (3) |" in md
    assert "| 2 / 3 | 7 +- 1.4 (2) |" in md
    assert "| BTR 3D cell | 1 / 2 | 60 (1) |" in md
    cmp = "\n".join(stratification.against_dem(rows))
    assert "| BTR 3D cell | DEM pour, rolling friction 0 | +38 | - | - | -0.2 | +0.2 | 0.01 |" in cmp
