"""Structural measures on configurations whose answers are known independently."""
import math

import numpy as np
import pytest

from btrdem import metrics
from btrdem.geometry import Container
from lattices import fcc, hexagonal_2d, peaks, simple_cubic, square_2d


def structure(pos, r, container, **kw):
    return metrics.structure(pos, r, np.ones(len(r), int), container, **kw)


def test_simple_cubic_packing_fraction_coordination_and_rdf_peaks():
    pos, r, L = simple_cubic(10, 12)
    s = structure(pos, r, Container("periodic", 3, L, L))
    assert s["packing_fraction"] == pytest.approx(math.pi / 6, abs=0.004)
    assert s["coordination"]["mean"] == 6.0
    assert s["coordination"]["distribution"]["6"] == 1.0
    # 12 layers, window from 2 d to 12 - 2 = 10 d: the 8 layers with centres 2.5 .. 9.5 d
    assert s["window"]["n_bulk_grains"] == 10 * 10 * 8
    found = peaks(s["rdf"]["r_over_d"], s["rdf"]["g"])
    for expected in (1.0, math.sqrt(2), math.sqrt(3), 2.0):
        assert np.min(np.abs(found - expected)) <= 0.025, (expected, found)
    # no neighbour closer than a diameter
    g = np.array(s["rdf"]["g"])
    assert np.all(g[np.array(s["rdf"]["r_over_d"]) < 0.97] == 0)


def test_fcc_packing_fraction_coordination_and_rdf_peaks():
    pos, r, L = fcc(6, 8)
    s = structure(pos, r, Container("periodic", 3, L, L))
    assert s["packing_fraction"] == pytest.approx(math.pi / (3 * math.sqrt(2)), abs=0.004)
    assert s["coordination"]["mean"] == 12.0
    assert s["coordination"]["distribution"]["12"] == 1.0
    found = peaks(s["rdf"]["r_over_d"], s["rdf"]["g"])
    for expected in (1.0, math.sqrt(2), math.sqrt(3), 2.0):
        assert np.min(np.abs(found - expected)) <= 0.025, (expected, found)
    # first shell: 12 neighbours at d. Integrate n * g * shell over the first peak.
    rd, g = np.array(s["rdf"]["r_over_d"]), np.array(s["rdf"]["g"])
    density = s["window"]["n_bulk_grains"] / s["window"]["volume"]
    first = (rd > 0.9) & (rd < 1.2)
    shell = 4 * math.pi * rd[first] ** 2 * 0.02
    assert np.sum(density * g[first] * shell) == pytest.approx(12.0, rel=0.03)


def test_box_walls_exclude_grains_near_them():
    pos, r, L = simple_cubic(10, 10)
    s = structure(pos, r, Container("box", 3, L, L))
    inner = (np.abs(pos[:, 0]) < 0.5 * L - 2) & (np.abs(pos[:, 1]) < 0.5 * L - 2) & (pos[:, 2] > 2) & (pos[:, 2] < 8)
    assert s["window"]["n_bulk_grains"] == int(inner.sum()) == 6 * 6 * 6
    assert s["coordination"]["mean"] == 6.0
    assert s["packing_fraction"] == pytest.approx(math.pi / 6, abs=0.006)


def test_two_dimensional_lattices():
    pos, r, L = square_2d(16, 12)
    s = structure(pos, r, Container("periodic", 2, L))
    assert s["packing_fraction"] == pytest.approx(math.pi / 4, abs=0.004)
    assert s["coordination"]["mean"] == 4.0
    pos, r, L = hexagonal_2d(16, 14)
    s = structure(pos, r, Container("periodic", 2, L))
    assert s["packing_fraction"] == pytest.approx(math.pi / (2 * math.sqrt(3)), abs=0.006)
    assert s["coordination"]["mean"] == 6.0
    found = peaks(s["rdf"]["r_over_d"], s["rdf"]["g"])
    for expected in (1.0, math.sqrt(3), 2.0):
        assert np.min(np.abs(found - expected)) <= 0.025, (expected, found)


def test_rigid_shift_is_the_displacement():
    pos, r, L = fcc(4, 4)
    c = Container("periodic", 3, L, L)
    d = 1.0
    for shift, above01, above05 in ((np.array([0.3, -0.2, 0.1]), 1.0, 0.0), (np.array([0.03, 0.0, 0.04]), 0.0, 0.0),
                                   (np.array([0.0, 0.6, 0.0]), 1.0, 1.0)):
        moved = pos + shift
        # wrap into the periodic domain, as an engine writes it back
        moved[:, :2] = np.mod(moved[:, :2] + 0.5 * L, L) - 0.5 * L
        disp = np.linalg.norm(metrics.displacement(pos, moved, c), axis=1) / d
        assert np.allclose(disp, np.linalg.norm(shift), atol=1e-12)
        st = metrics.displacement_stats(disp)
        assert st["fraction_above_0.1"] == above01
        assert st["fraction_above_0.5"] == above05
        assert st["max"] == pytest.approx(np.linalg.norm(shift), abs=1e-12)


def cone_heap(angle_deg, height, d=1.0):
    """FCC spheres under the cone z + r <= height - tan(angle) rho."""
    n = int(2 * height / math.tan(math.radians(angle_deg)) / (math.sqrt(2) * d)) + 2
    pos, r, L = fcc(n, int(height / (math.sqrt(2) * d)) + 2, d)
    rho = np.hypot(pos[:, 0], pos[:, 1])
    keep = pos[:, 2] + r <= height - math.tan(math.radians(angle_deg)) * rho
    return pos[keep], r[keep]


@pytest.mark.parametrize("angle", [22.0, 30.0, 38.0])
def test_heap_with_known_slope(angle):
    pos, r = cone_heap(angle, 12.0)
    c = Container("open", 3)
    coord, h = metrics.surface_profile(pos, r, c, 1.0, heap_axis=(0.0, 0.0))
    fit = metrics.angle_of_repose(coord, h)
    assert fit is not None and fit["n_points"] >= 5
    assert fit["angle_deg"] == pytest.approx(angle, abs=1.5)


def test_two_dimensional_heap_with_known_slope():
    angle = 26.0
    pos, r, L = hexagonal_2d(120, 40)
    keep = pos[:, 2] + r <= 25.0 - math.tan(math.radians(angle)) * np.abs(pos[:, 0])
    c = Container("open", 2)
    s = metrics.structure(pos[keep], r[keep], np.ones(int(keep.sum()), int), c, heap_axis=(0.0, 0.0))
    assert s["angle_of_repose"]["angle_deg"] == pytest.approx(angle, abs=1.5)


def test_segregation_index():
    pos, r, L = simple_cubic(6, 4)
    species = np.where(pos[:, 2] > 2.0, 2, 1)
    r = np.where(species == 2, 0.5, 0.25)  # large grains in the top two layers
    s = metrics.segregation_index(pos, r, species)
    zl, zs = 3.0, 1.0  # mean centre heights of layers (2.5, 3.5) and (0.5, 1.5)
    assert s["index"] == pytest.approx(2 * (zl - zs) / (zl + zs))
    # the same grains alternating in x: no vertical segregation
    species = np.where(np.round(pos[:, 0] + 2.5) % 2 == 0, 2, 1)
    r = np.where(species == 2, 0.5, 0.25)
    assert metrics.segregation_index(pos, r, species)["index"] == pytest.approx(0.0, abs=1e-12)
    assert metrics.segregation_index(pos, np.full(len(r), 0.5), np.ones(len(r), int)) is None


def test_contacts_across_the_periodic_boundary():
    L = 10.0
    pos = np.array([[-4.9, 0.0, 0.5], [4.6, 0.0, 0.5], [0.0, 0.0, 0.5]])
    r = np.full(3, 0.25)
    pairs, dist = metrics.contact_pairs(pos, r, Container("periodic", 3, L, L), tol=0.01)
    assert pairs.tolist() == [[0, 1]] and dist[0] == pytest.approx(0.5)
    pairs, _ = metrics.contact_pairs(pos, r, Container("box", 3, L, L), tol=0.01)
    assert len(pairs) == 0


def test_wide_size_ratio_contacts():
    # a big sphere touched by small ones all around: the wide-distribution search must find them
    big = np.array([[0.0, 0.0, 5.0]])
    dirs = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    small = big + dirs * (5.0 + 0.5)
    pos = np.vstack([big, small])
    r = np.array([5.0] + [0.5] * 6)
    pairs, _ = metrics.contact_pairs(pos, r, Container("open", 3))
    assert sorted(map(tuple, pairs.tolist())) == [(0, k) for k in range(1, 7)]
