"""dynamic-vs-dem (workflows/btrdem/studies/dynamic_vs_dem.py): the drum scenes' fills by hand, t90 and the
scatter-unit comparison on curves with known answers, and a tiny run of the whole study through both sides
(BTR and LIGGGHTS) with every run a row."""
import csv
import math
import shutil
import subprocess
import sys

import numpy as np
import pytest

from btrdem.studies import dynamic_vs_dem as dvd
from btrdem.studies import dynamic_vs_dem_report as dvr


@pytest.mark.parametrize("dim", [2, 3])
def test_drum_fill_has_equal_solid_fractions_and_the_asked_fill(dim):
    sc = dvd.drum_scene(dim, 0.4, 1)
    R = sc["container"]["radius"]
    n = sc["grains"]["count"]
    # Equal solid fractions of radii 0.5 and 1 mm: 2^dim small grains per large one.
    n_large = n / (1 + 2 ** dim)
    unit = math.pi if dim == 2 else 4 * math.pi / 3
    solid = n_large * unit * (1e-3 ** dim) * 2  # the large grains' solid, doubled
    space = math.pi * R * R * (1.0 if dim == 2 else sc["container"]["length"])
    phi_bulk = 0.8 if dim == 2 else 0.6
    assert solid / (space * phi_bulk) == pytest.approx(0.4, rel=2e-2)  # the count is rounded
    assert sc["grains"]["fraction_by"] == "volume"
    assert [c["fraction"] for c in sc["grains"]["component"]] == [0.5, 0.5]
    if dim == 3:
        assert sc["container"]["ends"] == "walls"


def test_t90_of_a_ramp_and_a_flat_curve():
    rev = np.linspace(0.0, 5.0, 501)
    ramp = np.minimum(rev, 1.0)  # final 1 (last fifth), start 0: 90 % at rev 0.9
    assert dvd.t90(rev, ramp) == pytest.approx(0.9, abs=1e-9)
    assert dvd.t90(rev, np.zeros_like(rev)) is None
    assert dvd.t90(rev, -ramp) is None  # falling: no rise to time


def test_comparison_in_dem_scatter_units():
    rows = [{"case": "c", "side": "btr", "froude": None, "seed": 1, "status": "ok", "core_end": 0.1,
             "cpu_per_rev": 2.0},
            {"case": "c", "side": "liggghts", "froude": 0.01, "seed": 1, "status": "ok", "core_end": 0.2,
             "cpu_per_rev": 300.0},
            {"case": "c", "side": "liggghts", "froude": 0.01, "seed": 2, "status": "ok", "core_end": 0.3,
             "cpu_per_rev": 500.0},
            {"case": "c", "side": "liggghts", "froude": 0.01, "seed": 3, "status": "fail", "reason": "x"}]
    comp = {c["measure"]: c for c in dvr.comparison(rows)}
    core = comp["core index (last rev)"]
    assert core["dem_n"] == 2  # the failed run is left out
    assert core["dem_mean"] == pytest.approx(0.25)
    assert core["dem_sd"] == pytest.approx(math.sqrt(0.005))
    assert core["error_sd"] == pytest.approx(-0.15 / math.sqrt(0.005))
    assert comp["CPU s per rev"]["ratio"] == pytest.approx(200.0)
    assert comp["dynamic angle [deg]"]["error_sd"] is None  # no values


def test_bad_parts_refused(tmp_path, source_dir):
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "dynamic-vs-dem",
                        "-o", str(tmp_path), "--parts", "drum,mixer"], capture_output=True, text=True)
    assert p.returncode == 2
    assert "--seeds/--parts" in p.stderr and "mixer" in p.stderr


def test_tiny_study_runs_both_sides(tmp_path, btr_binary, liggghts):
    res = dvd.run_dynamic_vs_dem(tmp_path, "liggghts", "tiny", seeds=(1,), parts=("drum", "brazil"),
                                 progress=lambda *_: None)
    assert [(r["side"], r["status"]) for r in res["drum"]] == [("btr", "ok"), ("liggghts", "ok")], res["drum"]
    assert [(r["side"], r["status"]) for r in res["brazil"]] == [("btr", "ok"), ("liggghts", "ok")], res["brazil"]
    dem = res["drum"][1]
    assert dem["revolutions"] == pytest.approx(0.1, abs=0.02)
    assert dem["cpu_per_rev"] > 0
    assert res["brazil"][1]["cycles"] == 1
    with open(tmp_path / "drum_vs_dem.csv") as f:
        measures = {r["measure"] for r in csv.DictReader(f)}
    assert "core index (last rev)" in measures
    text = (tmp_path / "report.md").read_text()
    assert "Dynamic BTR against DEM" in text and "liggghts" in text
    assert (tmp_path / "segregation_vs_dem.png").exists() and (tmp_path / "intruder_vs_dem.png").exists()
    # --reuse-runs: the finished drum runs are read back, not run again; a changed scene is run again.
    said = []
    again = dvd.run_dynamic_vs_dem(tmp_path, "liggghts", "tiny", seeds=(1,), parts=("drum",), progress=said.append,
                                   reuse_runs=True)
    assert sum("reused the run finished" in str(m) for m in said) == 2, said
    assert [r["core_end"] for r in again["drum"]] == [r["core_end"] for r in res["drum"]]
    run = tmp_path / "runs" / "drum2d_low" / "drum2d_low_btr_s1"
    scene = dvd.read_json(run / dvd.FINISHED)["scene"]
    argv = ["btr"] + dvd.read_json(run / dvd.FINISHED)["argv"]
    assert dvd.finished_run(run, scene, argv) is not None
    scene["drum"]["revolutions"] = 0.2
    assert dvd.finished_run(run, scene, argv) is None
    # --report-only from the runs moved to another folder: the finished ones are read, the others "not run".
    moved = tmp_path / "moved"
    shutil.copytree(tmp_path / "runs", moved / "runs")
    only = dvd.run_dynamic_vs_dem(moved, "liggghts", "tiny", seeds=(1, 2), parts=("drum", "mapping"),
                                  progress=lambda *_: None, report_only=True)
    # The mapping's BTR runs ran (one setting, two seeds) and are set against the DEM Froude number of the case.
    assert [(r["steps_per_revolution"], r["seed"], r["status"]) for r in only["mapping"]] == [(20, 1, "ok"), (20, 2, "ok")]
    with open(moved / "mapping.csv") as f:
        summary = list(csv.DictReader(f))
    assert len(summary) == 1 and "core_end_error_fr0.01" in summary[0] and float(summary[0]["btr_n"]) == 2
    assert "## Mapping" in (moved / "report.md").read_text() and (moved / "mapping.png").exists()
    said = []
    dvd.run_dynamic_vs_dem(moved, "liggghts", "tiny", seeds=(1, 2), parts=("drum", "mapping"), progress=said.append,
                           report_only=True)
    assert sum("[mapping] reused" in str(m) for m in said) == 2, said
    assert [(r["side"], r["seed"], r["status"]) for r in only["drum"]] == \
        [("btr", 1, "ok"), ("btr", 2, "not run"), ("liggghts", 1, "ok")], only["drum"]
    assert only["drum"][0]["core_end"] == res["drum"][0]["core_end"]
    assert "not run" in (moved / "report.md").read_text()
    with pytest.raises(dvd.InputError, match="--report-only"):
        dvd.run_dynamic_vs_dem(moved, "liggghts", "tiny", parts=("drum", "brazil"), report_only=True)
