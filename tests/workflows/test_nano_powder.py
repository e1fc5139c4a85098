"""nano-powder workflow: the saturation fit recovers known parameters; packing files with the cluster
column round-trip through the Python reader and writer."""
import numpy as np
import pytest

from btrdem.io import Packing, packing_csv_text, read_packing
from btrdem.nano_powder import fit_saturation, saturating


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
