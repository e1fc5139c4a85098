"""Structural measures, through `btr measure` (their one definition, btr/measures/metrics.cpp), on configurations
whose answers are known independently; displacement on rigid shifts."""
import math

import numpy as np
import pytest

from btrdem.analysis import measures
from btrdem.analysis.displacement import displacement, displacement_stats
from btrdem.core.geometry import Container
from btrdem.core.neighbours import touching_pairs
from lattices import fcc, hexagonal_2d, peaks, simple_cubic, square_2d
from scenes import packing_with_scene


@pytest.fixture
def measure(tmp_path, btr_binary):
    """measure(pos, r, kind, dim, L, **kw) -> `btr measure` of those grains in that container."""
    count = [0]

    def run(pos, r, kind="periodic", dim=3, L=0.0, source=None, species=None, **kw):
        count[0] += 1
        csv = packing_with_scene(tmp_path / f"p{count[0]}", "p", pos, r, kind, dim, L, source, species)
        return measures.measure(csv, btr=btr_binary, **kw)
    return run


def test_simple_cubic_packing_fraction_coordination_and_rdf_peaks(measure):
    pos, r, L = simple_cubic(10, 12)
    s = measure(pos, r, L=L, margin=2.0)
    assert s["bulk"]["window_margin_diameters"] == 2.0 and s["bulk"]["contact_tolerance"] == 1e-7
    assert measures.packing_fraction(s) == pytest.approx(math.pi / 6, abs=1e-12)
    assert measures.coordination(s) == 6.0
    assert measures.coordination_distribution(s)["6"] == 1.0
    # 12 layers, window from 2 d to 12 - 2 = 10 d: the 8 layers with centres 2.5 .. 9.5 d
    assert s["bulk"]["grains_in_window"] == 10 * 10 * 8
    found = peaks(*measures.rdf(s))
    for expected in (1.0, math.sqrt(2), math.sqrt(3), 2.0):
        assert np.min(np.abs(found - expected)) <= 0.025, (expected, found)
    # no neighbour closer than a diameter
    r_d, g = map(np.array, measures.rdf(s))
    assert np.all(g[r_d < 0.97] == 0)


def test_fcc_packing_fraction_coordination_and_rdf_peaks(measure):
    pos, r, L = fcc(6, 8)
    s = measure(pos, r, L=L, margin=2.0)
    assert measures.packing_fraction(s) == pytest.approx(math.pi / (3 * math.sqrt(2)), abs=0.01)
    assert measures.coordination(s) == 12.0
    assert measures.coordination_distribution(s)["12"] == 1.0
    r_d, g = map(np.array, measures.rdf(s))
    found = peaks(r_d, g)
    for expected in (1.0, math.sqrt(2), math.sqrt(3), 2.0):
        assert np.min(np.abs(found - expected)) <= 0.025, (expected, found)
    # first shell: 12 neighbours at d. Integrate n * g * shell over the first peak.
    density = s["bulk"]["grains_in_window"] / s["bulk"]["window_volume"]
    first = (r_d > 0.9) & (r_d < 1.2)
    shell = 4 * math.pi * r_d[first] ** 2 * 0.02
    assert np.sum(density * g[first] * shell) == pytest.approx(12.0, rel=0.03)


def test_box_walls_exclude_grains_near_them(measure):
    pos, r, L = simple_cubic(10, 10)
    s = measure(pos, r, "box", 3, L, margin=2.0)
    inner = (np.abs(pos[:, 0]) < 0.5 * L - 2) & (np.abs(pos[:, 1]) < 0.5 * L - 2) & (pos[:, 2] > 2) & (pos[:, 2] < 8)
    assert s["bulk"]["grains_in_window"] == int(inner.sum()) == 6 * 6 * 6
    assert measures.coordination(s) == 6.0
    assert measures.packing_fraction(s) == pytest.approx(math.pi / 6, abs=1e-9)


def test_two_dimensional_lattices(measure):
    pos, r, L = square_2d(16, 12)
    s = measure(pos, r, "periodic", 2, L, margin=2.0)
    assert measures.packing_fraction(s) == pytest.approx(math.pi / 4, abs=1e-12)
    assert measures.coordination(s) == 4.0
    pos, r, L = hexagonal_2d(16, 14)
    s = measure(pos, r, "periodic", 2, L, margin=2.0)
    assert measures.packing_fraction(s) == pytest.approx(math.pi / (2 * math.sqrt(3)), abs=0.006)
    assert measures.coordination(s) == 6.0
    found = peaks(*measures.rdf(s))
    for expected in (1.0, math.sqrt(3), 2.0):
        assert np.min(np.abs(found - expected)) <= 0.025, (expected, found)


def test_default_window_and_contact_rule_are_named_and_change_the_numbers(measure):
    pos, r, L = simple_cubic(10, 12)
    s = measure(pos, r, L=L)
    assert s["bulk"]["window_margin_diameters"] == 3.0  # the one default
    assert s["bulk"]["grains_in_window"] == 10 * 10 * 6  # centres 3.5 .. 8.5 d
    # columns spread apart laterally by a gap of 4e-6 radii: only the vertical contacts remain by default;
    # a tolerance of 1e-5 of the radius counts the lateral near-contacts too
    gapped = pos.copy()
    gapped[:, :2] *= 1.0 + 2e-6
    s = measure(gapped, r, L=L * (1 + 2e-6))
    assert s["bulk"]["valid"], s["bulk"]["note"]
    assert measures.coordination(s) == 2.0
    assert measures.coordination(measure(gapped, r, L=L * (1 + 2e-6), contact_tolerance=1e-5)) == 6.0


def test_rigid_shift_is_the_displacement():
    pos, r, L = fcc(4, 4)
    c = Container("periodic", 3, L, L)
    d = 1.0
    for shift, above01, above05 in ((np.array([0.3, -0.2, 0.1]), 1.0, 0.0), (np.array([0.03, 0.0, 0.04]), 0.0, 0.0),
                                   (np.array([0.0, 0.6, 0.0]), 1.0, 1.0)):
        moved = pos + shift
        # wrap into the periodic domain, as an engine writes it back
        moved[:, :2] = np.mod(moved[:, :2] + 0.5 * L, L) - 0.5 * L
        disp = np.linalg.norm(displacement(pos, moved, c), axis=1) / d
        assert np.allclose(disp, np.linalg.norm(shift), atol=1e-12)
        st = displacement_stats(disp)
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


def with_strays(pos, r, foot, n=30, layers=3):
    """Stacks of `layers` grains, far from the heap on a ring 1.5 to 3 times its foot radius: grains that
    rolled away. Their tops (3 d of a 12 d heap) stand above 20 % of its height."""
    k = np.arange(n)
    s = foot * (1.5 + 1.5 * k / (n - 1))
    a = 2.399963 * k
    stacks = [np.column_stack([s * np.cos(a), s * np.sin(a), np.full(n, 0.5 + l)]) for l in range(layers)]
    extra = np.vstack(stacks)
    return np.vstack([pos, extra]), np.concatenate([r, np.full(len(extra), 0.5)])


@pytest.mark.parametrize("strays", [False, True])
@pytest.mark.parametrize("angle", [22.0, 30.0, 38.0])
def test_heap_with_known_slope(measure, angle, strays):
    pos, r = cone_heap(angle, 12.0)
    if strays:
        pos, r = with_strays(pos, r, 12.0 / math.tan(math.radians(angle)))
    s = measure(pos, r, "open", 3, source={"kind": "point", "x": 0.0, "y": 0.0})
    h = s["heap"]
    assert h["valid"] and h["profile_points"] >= 5
    assert measures.angle_of_repose(s) == pytest.approx(angle, abs=1.5)
    if strays:
        assert h["grains_beyond_flank"] >= 90


def test_two_dimensional_heap_with_known_slope(measure):
    angle = 26.0
    pos, r, L = hexagonal_2d(120, 40)
    keep = pos[:, 2] + r <= 25.0 - math.tan(math.radians(angle)) * np.abs(pos[:, 0])
    s = measure(pos[keep], r[keep], "open", 2, source={"kind": "point", "x": 0.0, "y": 0.0})
    assert measures.angle_of_repose(s) == pytest.approx(angle, abs=1.5)


def test_segregation_index(measure):
    pos, r, L = simple_cubic(6, 4)
    species = np.where(pos[:, 2] > 2.0, 2, 1)
    r = np.where(species == 2, 0.5, 0.25)  # large grains in the top two layers
    s = measure(pos, r, L=L, species=species)["segregation"]
    zl, zs = 3.0, 1.0  # mean centre heights of layers (2.5, 3.5) and (0.5, 1.5)
    assert s["index"] == pytest.approx(2 * (zl - zs) / (zl + zs), abs=1e-14)
    # the same grains alternating in x: no vertical segregation
    species = np.where(np.round(pos[:, 0] + 2.5) % 2 == 0, 2, 1)
    r = np.where(species == 2, 0.5, 0.25)
    assert measures.segregation(measure(pos, r, L=L, species=species)) == pytest.approx(0.0, abs=1e-12)
    assert measures.segregation(measure(pos, np.full(len(r), 0.5), L=L)) is None


def test_contacts_across_the_periodic_boundary(measure):
    L = 10.0
    pos = np.array([[-4.9, 0.0, 0.5], [4.6, 0.0, 0.5], [0.0, 0.0, 0.5]])
    r = np.full(3, 0.25)
    s = measure(pos, r, "periodic", 3, L, per_grain=True)
    assert s["per_grain"]["coordination"].tolist() == [1, 1, 0]
    assert s["mean_coordination_all_grains"] == pytest.approx(2 / 3)
    s = measure(pos, r, "box", 3, L, per_grain=True)
    assert s["per_grain"]["coordination"].tolist() == [0, 0, 0]
    pairs, dist = touching_pairs(pos, r, Container("periodic", 3, L, L), tol=1e-9)
    assert pairs.tolist() == [[0, 1]] and dist[0] == pytest.approx(0.5)


def test_wide_size_ratio_contacts(measure):
    # a big sphere touched by small ones all around: both neighbour searches must find them
    big = np.array([[0.0, 0.0, 5.0]])
    dirs = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    pos = np.vstack([big, big + dirs * (5.0 + 0.5)])
    r = np.array([5.0] + [0.5] * 6)
    pairs, _ = touching_pairs(pos, r, Container("open", 3), tol=1e-9)
    assert sorted(map(tuple, pairs.tolist())) == [(0, k) for k in range(1, 7)]
    s = measure(pos, r, "open", 3, per_grain=True)
    assert s["per_grain"]["coordination"].tolist() == [6] + [1] * 6
