"""brazil-nut on tiny settings: every case a row, the deterministic model's known outcomes, the outputs."""
import csv
import json
import math
import subprocess
import sys

from btrdem.studies import brazil_nut


def test_brazil_nut_tiny(tmp_path, source_dir, btr_binary):
    out = tmp_path / "bn"
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "brazil-nut", "--tiny",
                        "--dims", "3", "-o", str(out)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    rows = {r["case"]: r for r in csv.DictReader(open(out / "brazil_nut.csv"))}
    # Per noise value: one bed without intruder and one case per Phi.
    assert len(rows) == len(brazil_nut.TINY_NOISES) * (1 + len(brazil_nut.TINY[3]["phis"]))
    assert all(r["status"] == "ok" for r in rows.values()), rows
    # Deterministic model, Phi = 1.5 < Phi_c: the intruder never leaves the floor (its centre stays at Phi/2).
    assert float(rows["3d_a0_phi1.5"]["z_end_d"]) == 0.75
    # Phi = 4 > Phi_c: it climbs, with and without noise.
    for a in brazil_nut.TINY_NOISES:
        r = rows[f"3d_a{a:g}_phi4"]
        assert float(r["z_end_d"]) > float(r["z0_d"]) + 1.5, r
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "ok" and run["summary"]["failed_cases"] == []
    report = (out / "report.md").read_text()
    assert "| 3D | 0 | between 1.5 and 4 |" in report  # the deterministic model: Phi = 4 rises, 1.5 does not
    for png in ("height_vs_cycles.png", "rise_vs_phi.png", "packing_vs_cycles.png"):
        assert (out / png).stat().st_size > 1000
    # Each case kept its snapshot series with the ParaView index.
    assert (out / "cases" / "3d_a0_phi4" / "shake.pvd").exists()


def test_summarise_and_threshold_by_hand():
    t = {"cycle": [0, 1, 2, 3], "seconds": [1.0, 0.1, 0.1, 0.1], "packing_fraction": [0.58, 0.59, 0.60, 0.61],
         "intruder_z_d": [2.0, 3.0, 4.0, 5.0], "intruder_below_top_d": [8.0, 7.0, 2.5, 2.0],
         "bed_top_d": [10.0] * 4, "intruder_z_over_bed_top": [0.2, 0.3, 0.4, 0.5]}
    t = {k: __import__("numpy").array(v, dtype=float) for k, v in t.items()}
    s = brazil_nut.summarise(t, 4.0)
    # Top within 1 d of the surface: below_top <= 4/2 + 1 = 3, first at cycle 2; rise (4 - 2) / 2 = 1 d per cycle.
    assert s["reached_top"] and s["cycles_to_top"] == 2
    assert math.isclose(s["rise_d_per_cycle"], 1.0)
    assert math.isclose(s["seconds_per_cycle"], 0.1)
    assert s["rose"]  # climbed 3 d >= RISE_D
    rows = [{"dimension": 3, "noise_d": 0.0, "phi": f, "status": "ok", "rose": f > 2.5, "reached_top": f > 3.5}
            for f in (2, 2.5, 3, 4)]
    assert brazil_nut.threshold(rows, 3, 0.0) == (2.5, 3, False)
    assert brazil_nut.threshold(rows, 3, 0.0, "reached_top") == (3, 4, False)
    rows.append({"dimension": 3, "noise_d": 0.0, "phi": 5.0, "status": "ok", "rose": False, "reached_top": False})
    assert brazil_nut.threshold(rows, 3, 0.0)[2]  # not monotonic in Phi: reported as such
