"""drum on tiny settings: every case a row with finite measures, the outputs, and summarise() by hand."""
import csv
import json
import math
import subprocess
import sys

import numpy as np

from btrdem.studies import drum


def test_drum_tiny(tmp_path, source_dir, btr_binary):
    out = tmp_path / "drum"
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "drum", "--tiny",
                        "-o", str(out)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    rows = list(csv.DictReader(open(out / "drum.csv")))
    assert [r["case"] for r in rows] == ["poly2d", "bi2d", "poly3d"]
    for r in rows:
        assert r["status"] == "ok", r
        assert math.isfinite(float(r["dynamic_angle_deg"])) and 0 < float(r["dynamic_angle_deg"]) < 90, r
        assert -1 < float(r["index_end"]) < 1, r
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "ok" and run["summary"]["failed_cases"] == []
    for png in ("segregation.png", "surface_angle.png", "snapshots.png"):
        assert (out / png).stat().st_size > 1000
    # One revolution of 20 steps: 21 rows per case, snapshots every 10 steps and a .pvd.
    steps = list(csv.DictReader(open(out / "cases" / "poly2d" / "drum2d_steps.csv")))
    assert len(steps) == 21 and float(steps[-1]["angle_deg"]) == 360.0
    assert (out / "cases" / "poly2d" / "drum2d.pvd").read_text().count("<DataSet") == 3


def test_summarise_by_hand():
    t = {"step": np.arange(5.0), "seconds": np.array([1.0, 0.2, 0.2, 0.2, 0.2]),
         "segregation_index": np.array([0.0, 0.1, 0.2, 0.3, 0.4]),
         "surface_angle_deg": np.array([0.0, 10.0, 20.0, 30.0, 40.0]),
         "core_small_R": np.array([0.5, 0.4, 0.3, 0.3, 0.2]), "core_large_R": np.array([0.5, 0.5, 0.5, 0.6, 0.6])}
    s = drum.summarise(t, 2)  # two steps per revolution: 2 revolutions; the last one is steps 3 and 4
    assert s["revolutions"] == 2.0
    assert s["index_one_rev"] == 0.2 and s["index_end"] == 0.4
    assert math.isclose(s["dynamic_angle_deg"], 35.0)
    assert math.isclose(s["seconds_per_step"], 0.2)
    # Core index large - small: 0 at fill, 0.2 after one revolution, mean of 0.3 and 0.4 over the last.
    assert s["core_index_0"] == 0.0 and math.isclose(s["core_index_one_rev"], 0.2)
    assert math.isclose(s["core_index_end_mean"], 0.35)
