"""Small scenes for the workflow tests: TOML files for `btr deposit`, and scene JSON for packings
built by the tests themselves."""
from pathlib import Path

import numpy as np

from btrdem.core.io import Packing, write_packing


def tiny_bed_toml(path: Path, count=150, size=0.007, max_time=0.05, young=5e6, engine="liggghts") -> str:
    path.write_text(f"""[scene]
name = "{path.stem}"
dimension = 3
seed = 3

[grains]
count = {count}
density = 2500.0
radius = {{ distribution = "uniform", min = 0.6e-3, max = 0.9e-3 }}

[container]
kind = "periodic"
size = [{size}, {size}]

[source]
kind = "rain"

[material]
young = {young}
poisson = 0.3
restitution = 0.5
friction = 0.5

[relax]
engine = "{engine}"
model = "hertz"
max_time = {max_time}
stop_kinetic_ratio = 1e-6
timestep_fraction = 0.2
""")
    return str(path)


def scene_json(kind="box", dim=3, size=0.01, gap=0.0, radius=0.0, source=None, count=100, max_time=0.1,
               rolling=0.0):
    src = {"kind": "rain", "x": 0.0, "y": 0.0, "scatter": 0.0, "x_min": 0.0, "x_max": 0.0, "y_min": 0.0,
           "y_max": 0.0, "file": ""}
    src.update(source or {})
    return {"name": "test", "file": "", "dimension": dim, "seed": 1,
            "grains": {"count": count, "fraction_by": "number", "components": [
                {"species": 1, "fraction": 1.0, "density": 2500.0,
                 "radius": {"kind": "uniform", "value": 0.0, "min": 0.8e-3, "max": 1.2e-3, "list": []},
                 "material": {"young": 5e6, "poisson": 0.3, "restitution": 0.5, "friction": 0.5,
                              "rolling_friction": rolling}}]},
            "container": {"kind": kind, "size_x": size, "size_y": size if dim == 3 and kind != "hele-shaw" else 0.0,
                          "gap": gap, "radius": radius, "height": 0.0},
            "source": src,
            "relax": {"engine": "liggghts", "model": "hertz", "max_time": max_time, "stop_kinetic_ratio": 1e-6,
                      "timestep_fraction": 0.2, "timestep": None}}


def grains_packing(directory: Path, scene: dict, seed=0) -> str:
    """A packing file holding the scene's grains (radii drawn here) at placeholder positions: the pour
    uses only the radii, species and scene."""
    n = scene["grains"]["count"]
    rng = np.random.default_rng(seed)
    r = rng.uniform(0.8e-3, 1.2e-3, n)
    pos = np.zeros((n, 3))
    pos[:, 2] = 1.2e-3 + np.arange(n) * 1e-5
    meta = {"scene": scene, "dimension": scene["dimension"], "container": scene["container"], "seed": seed}
    p = Packing(ids=np.arange(1, n + 1), pos=pos, radius=r, species=np.ones(n, int), meta=meta)
    return write_packing(directory, "btr", p)["csv"]


def packing_with_scene(directory: Path, name: str, pos, r, kind="periodic", dim=3, size=0.0, source=None,
                       species=None) -> str:
    """DIR/NAME.csv + NAME.json of given grains, with a full scene (container `kind`, lateral size `size`,
    source) so that `btr measure` and `btr relax` can read it. Returns the CSV path."""

    n = len(r)
    scene = scene_json(kind, dim, size=size, source=source, count=n)
    meta = {"scene": scene, "dimension": dim, "container": scene["container"]}
    sp = np.ones(n, int) if species is None else np.asarray(species)
    p = Packing(ids=np.arange(1, n + 1), pos=np.asarray(pos, float), radius=np.asarray(r, float), species=sp, meta=meta)
    return write_packing(directory, name, p, vtp=False)["csv"]
