"""The reference pour through `btr pour` (btrdem.dem.pour): grains end at rest inside the container, as a random
packing; the lattice and plan are tested in tests/coupling/test_pour_plan.cpp."""
import numpy as np
import pytest

from btrdem.analysis import measures
from btrdem.core.neighbours import touching_pairs
from btrdem.core.io import read_packing
from btrdem.dem.pour import PourFailure, PourSettings, finished_pour, pour
from scenes import grains_packing, scene_json


def quiet(msg):
    pass


def test_pour_into_a_box_is_a_random_packing_at_rest(tmp_path, liggghts):
    scene = scene_json("box", 3, size=0.012, count=220, max_time=0.15)
    btr = read_packing(grains_packing(tmp_path / "btr", scene))
    s = pour(btr, tmp_path / "pour", PourSettings(seed=2), quiet)
    q = read_packing(s["packing"])
    assert np.array_equal(q.ids, btr.ids) and np.allclose(q.radius, btr.radius)
    c = q.container()
    assert np.all(c.wall_distance(q.pos) >= q.radius * 0.97)          # inside the walls
    assert np.all(q.pos[:, 2] >= q.radius * 0.97)                     # above the floor
    pairs, dist = touching_pairs(q.pos, q.radius, c, tol=0.0)
    overlap = (q.radius[pairs[:, 0]] + q.radius[pairs[:, 1]] - dist) / np.minimum(q.radius[pairs[:, 0]],
                                                                                  q.radius[pairs[:, 1]])
    assert overlap.max() < 0.05
    st = measures.measure(s["packing"], margin=1.5)
    # a poured frictional packing lies between random loose and random close packing
    assert 0.53 < measures.packing_fraction(st) < 0.66
    assert 4.0 < measures.coordination(st) < 7.5
    kin = np.genfromtxt(tmp_path / "pour" / "kinetic.csv", delimiter=",", skip_header=1)
    assert kin[-1, 1] < 1e-3 * kin[:, 1].max()                        # came to rest
    assert s["stop_reason"] in ("kinetic-energy", "max-time")
    assert (tmp_path / "pour" / "in.btr").exists() and (tmp_path / "pour" / "log.liggghts").exists()
    assert s["timestep_rule"].startswith("Rayleigh time") and s["engine"] == "liggghts"
    assert finished_pour(btr, tmp_path / "pour", PourSettings(seed=2))["reused"]
    assert finished_pour(btr, tmp_path / "pour", PourSettings(seed=3)) is None  # another seed is another pour


def test_two_dimensional_pour_stays_in_the_plane(tmp_path, liggghts):
    scene = scene_json("box", 2, size=0.02, count=60, max_time=0.1)
    btr = read_packing(grains_packing(tmp_path / "btr", scene))
    s = pour(btr, tmp_path / "pour", PourSettings(seed=1), quiet)
    q = read_packing(s["packing"])
    assert np.all(q.pos[:, 1] == 0.0)
    assert np.all(np.abs(q.pos[:, 0]) <= 0.01 - q.radius * 0.97)
    # disks at rest form at least one layer on the floor: the lowest centres sit at their radius
    assert np.min(q.pos[:, 2] - q.radius) > -0.03 * q.radius.min()


def test_rain_on_an_open_floor_is_refused(tmp_path):
    scene = scene_json("open", 3, count=10)
    btr = read_packing(grains_packing(tmp_path / "btr", scene))
    with pytest.raises(PourFailure, match="source.kind"):
        pour(btr, tmp_path / "pour", PourSettings(), quiet)


def test_open_floor_pour_removes_and_counts_runaway_grains(tmp_path, liggghts):
    """An open floor is bounded as btr relax bounds it: the box is fixed laterally at the footprint +
    relax.open_margin largest diameters, and grains that slide out of it are removed and counted (a
    shrink-wrapped box grew with every runaway grain instead)."""
    # Rolling friction holds a small heap (without it spheres roll away on the flat floor for ever); a region one
    # largest diameter beyond the footprint is narrower than the heap, so its flanks leave.
    scene = scene_json("open", 3, size=0.0, count=60, max_time=0.3, source={"kind": "point"}, rolling=0.1)
    scene["relax"]["open_margin"] = 1.0
    scene["relax"]["open_heap_angle"] = 80.0  # a heap bound narrower than this heap too
    btr = read_packing(grains_packing(tmp_path / "btr", scene))
    s = pour(btr, tmp_path / "pour", PourSettings(seed=3, max_batches=4), quiet)
    assert 0 < s["removed"] < len(btr)
    q = read_packing(s["packing"])
    assert len(q) + s["removed"] == len(btr)
    assert np.array_equal(q.ids, np.arange(1, len(q) + 1))  # the others keep their order, renumbered
    removed = np.array(q.meta["pour"]["removed"]["ids"])
    kept = np.setdiff1d(np.arange(1, len(btr) + 1), removed) - 1
    assert len(removed) == s["removed"] and np.allclose(q.radius, btr.radius[kept])
    assert "boundary        f f fm" in (tmp_path / "pour" / "in.btr").read_text()
    data = (tmp_path / "pour" / "btr.data").read_text().splitlines()
    xlo, xhi = (float(v) for v in next(line for line in data if line.endswith("xlo xhi")).split()[:2])
    ylo, yhi = (float(v) for v in next(line for line in data if line.endswith("ylo yhi")).split()[:2])
    d_max = 2 * btr.radius.max()
    # the region holds the BTR footprint grown by one largest diameter, and every grain still in the run
    assert xlo <= -btr.radius.max() - d_max + 1e-12 and xhi >= btr.radius.max() + d_max - 1e-12
    assert xhi - xlo < 20 * d_max  # fixed near the footprint, not grown by the runaway grains
    assert np.all((q.pos[:, 0] >= xlo) & (q.pos[:, 0] <= xhi) & (q.pos[:, 1] >= ylo) & (q.pos[:, 1] <= yhi))
    assert np.all(q.pos[:, 2] >= q.radius * 0.97)
