"""BTR support analysis on hand-built configurations with known contact geometry."""
import math

import numpy as np
import pytest

from btrdem.core.geometry import Container
from btrdem.analysis.support import btr_supports, polygon_margin


def line_distance(p, a, b):
    """Signed distance of p from the line a-b, positive on the side of the triangle's interior (left
    of a->b for a counter-clockwise triangle)."""
    e = (b - a) / np.linalg.norm(b - a)
    return (e[0] * (p[1] - a[1]) - e[1] * (p[0] - a[0]))


def triangle_margin(p, tri):
    tri = np.array(tri, float)
    if np.cross(tri[1] - tri[0], tri[2] - tri[0]) < 0:
        tri = tri[[0, 2, 1]]
    return min(line_distance(p, tri[k], tri[(k + 1) % 3]) for k in range(3))


def circumcentre(a, b, c):
    d = 2 * (a[0] * (b[1] - c[1]) + b[0] * (c[1] - a[1]) + c[0] * (a[1] - b[1]))
    ux = ((a @ a) * (b[1] - c[1]) + (b @ b) * (c[1] - a[1]) + (c @ c) * (a[1] - b[1])) / d
    uy = ((a @ a) * (c[0] - b[0]) + (b @ b) * (a[0] - c[0]) + (c @ c) * (b[0] - a[0])) / d
    return np.array([ux, uy])


@pytest.mark.parametrize("base", [
    [(0.0, 0.0), (2.0, 0.0), (1.0, math.sqrt(3.0))],   # touching triangle, centre above the centroid
    [(0.0, 0.0), (2.6, 0.0), (0.9, 1.9)],              # acute, off-centre
    [(0.0, 0.0), (3.2, 0.0), (1.6, 1.25)],             # obtuse: the centre projects outside
])
def test_grain_on_three_grains(base):
    base = np.array(base)
    p = circumcentre(*base)
    rc = np.linalg.norm(base[0] - p)
    assert rc < 2.0
    pos = np.array([[x, y, 1.0] for x, y in base] + [[p[0], p[1], 1.0 + math.sqrt(4.0 - rc * rc)]])
    r = np.ones(4)
    s = btr_supports(pos, r, Container("open", 3))
    assert list(s["kind"]) == ["floor", "floor", "floor", "3"]
    touching = [sum(np.linalg.norm(base[i] - base[j]) <= 2.0 + 1e-12 for j in range(i)) for i in range(3)]
    assert s["n_supports"].tolist() == [1 + t for t in touching] + [3]
    assert s["load"].tolist() == [1, 1, 1, 0]
    # equal radii: contact points are the midpoints; their triangle is the base triangle halved about p
    contacts = p + 0.5 * (base - p)
    expected = triangle_margin(p, contacts)
    assert s["edge_distance"][3] == pytest.approx(expected, abs=1e-9)
    if base[2][1] == pytest.approx(math.sqrt(3.0)):
        assert expected == pytest.approx(1.0 / math.sqrt(3.0) / 2.0, abs=1e-12)  # inradius of the contact triangle
    assert np.isnan(s["edge_distance"][:3]).all()


def test_disk_on_two_disks_and_a_wall_in_2d():
    # two floor disks of radii 0.5 and 0.8; a disk of radius 0.6 resting on both
    r = np.array([0.5, 0.8, 0.6, 0.5])
    a, b = np.array([0.0, 0.5]), np.array([2.0, 0.8])
    # top centre t: |t - a| = 1.1, |t - b| = 1.4 (circle intersection, upper solution)
    d = np.linalg.norm(b - a)
    l = (1.1 ** 2 - 1.4 ** 2 + d * d) / (2 * d)
    h = math.sqrt(1.1 ** 2 - l * l)
    e = (b - a) / d
    t = a + l * e + h * np.array([-e[1], e[0]])
    # a fourth disk (r = 0.5) against the wall x = -1.5 resting on disk 1
    L = 4.6
    a, b, t = a - [0.9, 0], b - [0.9, 0], t - [0.9, 0]
    w = np.array([-1.8, 0.0])
    w[1] = 0.5 + math.sqrt(1.0 - (w[0] - a[0]) ** 2)
    pos = np.array([[a[0], 0, a[1]], [b[0], 0, b[1]], [t[0], 0, t[1]], [w[0], 0, w[1]]])
    s = btr_supports(pos, r, Container("box", 2, L))
    assert list(s["kind"]) == ["floor", "floor", "2", "2"]
    assert s["walls"].tolist() == [0, 0, 0, 1]
    xa = t[0] + 0.6 * (a[0] - t[0]) / 1.1
    xb = t[0] + 0.6 * (b[0] - t[0]) / 1.4
    assert s["edge_distance"][2] == pytest.approx(min(t[0] - xa, xb - t[0]) / 0.6, abs=1e-9)
    # wall contact at x = -2.3; grain contact half way to disk 1's centre
    xc = w[0] + 0.5 * (a[0] - w[0])
    assert s["edge_distance"][3] == pytest.approx(min(w[0] + 2.3, xc - w[0]) / 0.5, abs=1e-9)


def test_polygon_margin_segment_and_square():
    m, off, deg = polygon_margin(np.array([[-1.0, 0.2], [2.0, 0.2]]))
    assert deg and m == pytest.approx(1.0) and off == pytest.approx(0.2)
    m, off, deg = polygon_margin(np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]) + [0.25, 0.0])
    assert not deg and m == pytest.approx(0.75) and off == 0.0


def test_periodic_support_across_the_boundary():
    L = 4.0
    # base grains straddle x = +-L/2; the top grain sits above the seam
    base = np.array([[-1.9, -0.6], [1.7, -0.6], [1.9, 0.9]])  # 1.7 and 1.9 are images at -2.3 and -2.1
    unwrapped = base.copy()
    unwrapped[1:, 0] -= L
    p = circumcentre(*unwrapped)
    rc = np.linalg.norm(unwrapped[0] - p)
    pos = np.array([[x, y, 1.0] for x, y in base] + [[p[0], p[1], 1.0 + math.sqrt(4.0 - rc * rc)]])
    s = btr_supports(pos, np.ones(4), Container("periodic", 3, L, L))
    assert s["kind"][3] == "3"
    assert s["edge_distance"][3] == pytest.approx(triangle_margin(p, p + 0.5 * (unwrapped - p)), abs=1e-9)
