"""nano-powder workflow: the saturation fit recovers known parameters; packing files with the cluster
column round-trip through the Python reader and writer; the workflow on tiny settings averages its
3D seeds."""
import csv
import os
import subprocess
import sys

import numpy as np
import pytest

from btrdem.core.io import Packing, packing_csv_text, read_packing
from btrdem.studies.nano_powder import fit_saturation, mean_over_seeds, read_cycles, saturating


def test_fit_recovers_known_parameters_with_honest_errors():
    rng = np.random.default_rng(3)
    n = np.arange(1, 19, dtype=float)
    h = saturating(n, 9450.0, 5000.0, 6.0) + rng.normal(0.0, 20.0, n.size)
    f = fit_saturation(n, h)
    for key, true in (("a", 9450.0), ("b", 5000.0), ("tau", 6.0)):
        assert abs(f[key] - true) < 4 * f[key + "_err"], (key, f)
        assert 0 < f[key + "_err"] < 0.1 * abs(true)


def test_fit_flags_data_without_saturation():
    rng = np.random.default_rng(5)
    n = np.arange(1, 13, dtype=float)
    flat = 115.0 + rng.normal(0.0, 5.0, n.size)
    flat[0] += 10.0  # one high first point: curve_fit drives tau to its bound
    assert not fit_saturation(n, flat)["determined"]
    assert fit_saturation(n, saturating(n, 34.0, 7.0, 3.0) + rng.normal(0, 0.2, n.size))["determined"]


def test_fit_refuses_too_few_cycles():
    with pytest.raises(ValueError, match="at least 3 cycles"):
        fit_saturation([1, 2], [1.0, 2.0])


def test_cluster_column_round_trips(tmp_path):
    p = Packing(ids=np.arange(1, 5), pos=np.arange(12, dtype=float).reshape(4, 3) * 1e-3,
                radius=np.full(4, 1e-3), species=np.ones(4, dtype=int), cluster=np.array([1, 1, 0, 2]))
    text = packing_csv_text(p)
    assert text.splitlines()[0] == "id,x,y,z,radius,species,cluster"
    (tmp_path / "c.csv").write_text(text)
    q = read_packing(tmp_path / "c.csv")
    assert list(q.cluster) == [1, 1, 0, 2]
    free = Packing(ids=p.ids, pos=p.pos, radius=p.radius, species=p.species)
    assert packing_csv_text(free).splitlines()[0] == "id,x,y,z,radius,species"
    (tmp_path / "f.csv").write_text(packing_csv_text(free))
    assert read_packing(tmp_path / "f.csv").cluster is None


def test_workflow_tiny_averages_the_seeds(tmp_path, source_dir, btr_binary):
    """Both cases pass the cluster check in every cycle; the 3d row is the mean of its seeds' own
    series (read back from their cycles files), and the figure and report are written (into a relative
    -o: btr runs inside it)."""
    cycles = 4
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "nano-powder", "--tiny",
                        "--cycles", str(cycles), "-o", "out"], capture_output=True, text=True, cwd=tmp_path,
                       env={**os.environ, "BTR_BINARY": btr_binary}, timeout=300)
    assert p.returncode == 0, p.stderr
    tmp_path = tmp_path / "out"
    with open(tmp_path / "nano_powder.csv") as f:
        rows = {r["case"]: r for r in csv.DictReader(f)}
    assert set(rows) == {"2d", "3d"}
    for r in rows.values():
        assert r["status"] == "ok", r
        assert np.isfinite(float(r["a"])), r
    seeds = rows["3d"]["seeds"].split()
    assert len(seeds) == 2
    runs = [read_cycles(tmp_path / "cases" / "3d" / f"seed{s}" / "nano_powder3d_cycles.csv") for s in seeds]
    for t in runs:
        assert list(t["cycle"]) == list(range(cycles + 1))
    assert not np.array_equal(runs[0]["mean_height_d"], runs[1]["mean_height_d"])  # the seeds differ
    last = np.mean([t["mean_height_d"][-1] for t in runs])
    assert float(rows["3d"]["h_last_d"]) == pytest.approx(last, rel=1e-12)
    assert float(rows["3d"]["h0_d"]) == pytest.approx(np.mean([t["mean_height_d"][0] for t in runs]), rel=1e-12)
    assert (tmp_path / "mean_height.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "![mean height](mean_height.png)" in (tmp_path / "report.md").read_text()


def test_mean_over_seeds_and_its_error():
    a = {"cycle": np.arange(3.0), "mean_height_d": np.array([1.0, 2.0, 3.0]), "seconds": np.ones(3)}
    b = {"cycle": np.arange(3.0), "mean_height_d": np.array([3.0, 2.0, 5.0]), "seconds": np.ones(3)}
    m = mean_over_seeds([a, b])
    assert list(m["mean_height_d"]) == [2.0, 2.0, 4.0]
    assert list(m["seconds"]) == [2.0, 2.0, 2.0]
    # standard error of two values x, y: |x - y| / 2
    assert m["mean_height_err"] == pytest.approx([1.0, 0.0, 1.0])
    assert np.all(np.isnan(mean_over_seeds([a])["mean_height_err"]))
    with pytest.raises(ValueError, match="different cycles"):
        mean_over_seeds([a, {**b, "cycle": np.arange(1.0, 4.0)}])
