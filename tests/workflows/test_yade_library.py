"""The YADE script library (coupling/yade/yade_library.py): a real Python file, embedded by the build into
every YADE script btr writes. Its helpers are tested here against values computed by hand."""
import importlib.util
import math
import subprocess
import sys

import pytest

YADE_PATH = "/usr/lib/x86_64-linux-gnu/yade-double/py"


@pytest.fixture()
def library(tmp_path, source_dir, monkeypatch):
    """The library loaded as a module whose folder (HERE, taken from argv[0]) is tmp_path."""
    (tmp_path / "yade_status.json").write_text("stale\n")  # an earlier run's output
    monkeypatch.setattr(sys, "argv", [str(tmp_path / "relax_yade.py")])
    monkeypatch.syspath_prepend(YADE_PATH)
    spec = importlib.util.spec_from_file_location("btr_yade_library", source_dir / "coupling/yade/yade_library.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_stale_outputs_are_removed_on_start(library, tmp_path):
    assert not (tmp_path / "yade_status.json").exists()


def test_wrap_gives_the_minimum_image(library):
    assert library.wrap(0.7, 1.0) == pytest.approx(-0.3)
    assert library.wrap(-0.7, 1.0) == pytest.approx(0.3)
    assert library.wrap(0.2, 1.0) == pytest.approx(0.2)
    assert library.wrap(2.2, 1.0) == pytest.approx(0.2)


@pytest.mark.parametrize("dimension", [2, 3])
def test_grain_part_between_planes(library, dimension):
    library.DIMENSION = dimension
    r, z = 0.5, 3.0
    whole = 4.0 / 3.0 * math.pi * r ** 3 if dimension == 3 else math.pi * r ** 2
    assert library.grain_part_between(z, r, -10.0, 10.0) == pytest.approx(whole)
    assert library.grain_part_between(z, r, z, 10.0) == pytest.approx(0.5 * whole)
    assert library.grain_part_between(z, r, z + r, 10.0) == 0.0
    # a cap of height h = r/2: pi h^2 (3r - h) / 3 in 3D; r^2 acos((r-h)/r) - (r-h) sqrt(2rh - h^2) in 2D
    h = 0.5 * r
    cap = (math.pi * h * h * (3 * r - h) / 3.0 if dimension == 3
           else r * r * math.acos((r - h) / r) - (r - h) * math.sqrt(2 * r * h - h * h))
    assert library.grain_part_between(z, r, z + r - h, 10.0) == pytest.approx(cap)


def test_slab_twins_make_only_their_pairs_frictionless(library):
    """A compaction in slabs: a pair with a twin material (a slab grain against anything) takes the scaled
    friction, every other pair the scene's; without twins every pair is scaled."""
    library._pairs[:] = [(0, 0, 0.5, 0.5), (0, 1, 0.4, 0.3)]  # species 0 with itself and with the walls (1)
    library._twins.clear()
    assert sorted(library.pair_values(0.5)) == [(0, 0, 0.5, 0.25), (0, 1, 0.4, 0.15)]
    library._twins[0] = 2
    friction = {(a, b): mu for a, b, _, mu in library.pair_values(0.0)}
    assert friction[(0, 0)] == 0.5 and friction[(0, 1)] == 0.3
    assert friction[(2, 0)] == friction[(0, 2)] == friction[(2, 2)] == friction[(2, 1)] == 0.0
    assert (1, 1) not in friction and (1, 2) not in friction  # walls have no twin
    restitution = {(a, b): e for a, b, e, _ in library.pair_values(1.0)}
    assert restitution[(2, 1)] == 0.4 and restitution[(2, 2)] == 0.5


def test_write_atomically_leaves_only_the_file(library, tmp_path):
    library.write_atomically("out.txt", "one\n")
    library.write_atomically("out.txt", "two\n")
    assert (tmp_path / "out.txt").read_text() == "two\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


def test_every_yade_script_carries_the_library(tmp_path, source_dir, btr_binary):
    """btr writes the file's code (less its leading comment block) into each script it exports."""
    subprocess.run([btr_binary, "deposit", str(source_dir / "inputs/bed3d.toml"), "-o", str(tmp_path / "bed"),
                    "--count", "60"], check=True, capture_output=True)
    subprocess.run([btr_binary, "export", str(tmp_path / "bed/bed3d.csv"), "--to", "yade", "-o",
                    str(tmp_path / "yade")], check=True, capture_output=True)
    text = (source_dir / "coupling/yade/yade_library.py").read_text()
    code = text[text.index("\nimport ") + 1:]
    scripts = list((tmp_path / "yade").glob("*.py"))
    assert len(scripts) == 1
    assert code in scripts[0].read_text()


def test_run_failure_carries_its_kind(library):
    # the kind the script writes as yade_status.json's failure_kind (a FailureKind name, coupling/dem/relax.h)
    assert library.RunFailure("boom").kind == "engine_error"
    e = library.RunFailure("blow-up: ...", "blow_up")
    assert e.kind == "blow_up" and str(e) == "blow-up: ..."


def build_engines_for_one_species(library, periodic, gravity, pour=None):
    """A fresh YADE scene of one Hertz species (VERLET_DIST 1e-4 m), in a 1 cm periodic cell if asked, with the
    library's engines built as a relaxation's (pour None) or a pour's."""
    library.MODEL, library.COMPACTION, library.DAMPING, library.GRAVITY = "hertz", None, 0.0, gravity
    library.POUR = pour
    library.VERLET_DIST = 1e-4
    library._pairs[:] = [(0, 0, 0.5, 0.5)]
    library._cell = None
    library.O.reset()
    if periodic:
        library.periodic_cell(0.01, 0.01, 0.1)
    library.build_engines()


@pytest.mark.parametrize("periodic", [True, False])
def test_a_periodic_cells_collider_searches_every_pair_at_every_run(library, periodic):
    """YADE's incremental periodic sort let two grains whose boxes straddled the cell's boundary pass into each
    other (a pour, coupling/README.md "Open floors"): in a periodic cell every collider run finds every pair
    whose boxes overlap; a walled container keeps YADE's incremental search."""
    build_engines_for_one_species(library, periodic, gravity=9.81)
    collider = library._collider
    assert collider.sortThenCollide is periodic
    assert collider.allowBiggerThanPeriod is periodic
    assert collider.sortAxis == (2 if periodic else 0)


@pytest.mark.parametrize("pour", [False, True])
def test_a_periodic_cells_boxes_keep_the_whole_margin_where_nothing_falls(library, pour):
    """Every full search costs about N^2 / depth, so in a periodic cell a relaxation's boxes keep the whole margin
    and the search runs only when a grain has left its box. YADE's default (targetInterv) shrinks a slow grain's
    box, down to nothing for a grain at rest, and a bed near rest then searched every few steps (954 searches
    against 18 in a 10^4-grain settle, coupling/README.md). A pour keeps the default: its falling grains run the
    search often anyway, and the pile's small boxes save pairs (1469 grains: 50 s against 62 s)."""
    build_engines_for_one_species(library, True, gravity=0.0, pour={"batches": []} if pour else None)
    drifting = library.utils.sphere((0.002, 0.005, 0.05), 5e-4)
    at_rest = library.utils.sphere((0.007, 0.005, 0.05), 5e-4)
    library.O.bodies.append([drifting, at_rest])
    drifting.state.vel = library.Vector3(0.02, 0.0, 0.0)
    library.O.dt = 1e-5
    library.O.run(900, True)  # with the whole margin the drifting grain leaves its box once, after 500 steps
    if pour:
        assert at_rest.bound.sweepLength < 0.5 * library.VERLET_DIST
        return
    assert library._collider.numAction == 2
    for grain in (drifting, at_rest):
        assert grain.bound.sweepLength == pytest.approx(library.VERLET_DIST, rel=1e-12)
