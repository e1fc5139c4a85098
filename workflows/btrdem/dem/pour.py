"""Reference DEM pour in LIGGGHTS: the grains of a BTR packing (same radii, species, container and
source) poured and left to come to rest.

How the pour works (the input is written here, LIGGGHTS 3.8 syntax):
- Every grain starts on a loose lattice (spacing 1.1 x the largest diameter, with a seeded jitter)
  held high above the container, over the source's footprint: the container's floor for rain, the
  rectangle of a region source, a disk about the drop point for a point source. Grains take lattice
  sites in id (BTR deposition) order, lowest layers first. Held grains are not integrated, so they
  do not move.
- The lattice is released in batches of consecutive layers: each batch is moved down until its
  lowest centre is `drop_gap_d` mean diameters plus one largest diameter above the highest grain
  already released, joins the integrated group, and falls. The next batch follows after `pace`
  times the batch's free-fall time. A pour is thus a stream from a small, constant drop height.
- After the last batch the run continues in chunks until the kinetic energy (translational +
  rotational) falls below stop_ratio * sum_i m_i g d_i, or until max_time.
- 2D scenes (disks in the x-z plane) are run as spheres whose y force is held at zero.
Contact model: Hertz (or Hooke) with tangential history, the scene's material, walls for the
container (floor z = 0; none laterally for open and periodic containers, periodic boundaries for
the latter). Open floors are bounded as `btr relax` bounds them (coupling/README.md, "Open floors"):
the box is fixed laterally at the grains' footprint (the BTR packing's and the pour lattice's) grown by
relax.open_margin largest diameters, and a grain whose centre leaves it is lost to LIGGGHTS, i.e.
removed, and counted (poured.json "removed", the summary's "removed"); the others keep their order,
renumbered. A shrink-wrapped box grew with every runaway grain until binning took most of each step. Time step: the Rayleigh time of the smallest grain times the scene's fraction.
"""
from __future__ import annotations

import math
import os
import shutil
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from . import dem_params
from ..core.geometry import Container
from ..core.io import Packing, atomic_write_text, read_json, read_packing, write_json, write_packing
from ..core.runner import StepFailed, run_command


@dataclass
class PourSettings:
    seed: int = 1
    np: int = 1                        # MPI ranks
    pace: float = 1.0                  # batch interval / batch free-fall time (smaller: faster pour)
    drop_gap_d: float = 1.0            # drop height above the highest released grain [mean diameters]
    max_batches: int = 40
    stop_ratio: float | None = None    # default: the scene's relax.stop_kinetic_ratio
    settle_max_time: float | None = None  # simulated seconds after the last batch; default scene relax.max_time
    timestep_fraction: float | None = None  # default: the scene's relax.timestep_fraction
    check_every: float = 0.005         # simulated seconds between kinetic-energy checks
    wall_time_limit: float = 7200.0
    label: str = "pour"
    extra: dict = field(default_factory=dict)


class PourFailure(StepFailed):
    pass


def _footprint_sites(container: Container, scene: dict, spacing: float, r_max: float, rng) -> np.ndarray:
    """Lateral lattice sites (k, 2) = (x, y) of one layer (y = 0 in 2D)."""
    src = scene.get("source") or {}
    kind = src.get("kind", "rain")
    dim = container.dimension
    margin = 1.05 * r_max

    def grid(lo, hi, periodic=False):
        span = hi - lo
        if periodic:
            n = max(1, int(math.floor(span / spacing)))
            return lo + (np.arange(n) + 0.5) * (span / n)
        n = max(1, int(math.floor((span - 2 * margin) / spacing)) + 1)
        if n == 1:
            return np.array([0.5 * (lo + hi)])
        step = (span - 2 * margin) / (n - 1)
        return lo + margin + step * np.arange(n)

    if kind == "region":
        xs = grid(src["x_min"] - margin, src["x_max"] + margin)
        ys = grid(src["y_min"] - margin, src["y_max"] + margin) if dim == 3 else np.array([0.0])
    elif kind == "point":
        x0, y0 = float(src.get("x", 0.0)), float(src.get("y", 0.0))
        reach = max(float(src.get("scatter", 0.0)), 1.5 * spacing)
        n = int(math.ceil(reach / spacing))
        offs = np.arange(-n, n + 1) * spacing
        if dim == 3:
            gx, gy = np.meshgrid(offs, offs, indexing="ij")
            keep = np.hypot(gx, gy) <= reach + 1e-12
            pts = np.column_stack([x0 + gx[keep], y0 + gy[keep]])
        else:
            pts = np.column_stack([x0 + offs, np.zeros(len(offs))])
        return _clip_to_container(pts, container, r_max)
    else:  # rain, list: the container's footprint
        if container.kind in ("box", "periodic"):
            per = container.kind == "periodic"
            xs = grid(-0.5 * container.size_x, 0.5 * container.size_x, per)
            ys = grid(-0.5 * container.size_y, 0.5 * container.size_y, per) if dim == 3 else np.array([0.0])
        elif container.kind == "hele-shaw":
            xs = grid(-0.5 * container.size_x, 0.5 * container.size_x)
            ys = grid(-0.5 * container.gap, 0.5 * container.gap)
        elif container.kind == "cylinder":
            xs = ys = grid(-container.radius, container.radius)
        else:
            raise PourFailure("pour: a rain source needs a container footprint (open container)")
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    return _clip_to_container(np.column_stack([gx.ravel(), gy.ravel()]), container, r_max)


def _clip_to_container(pts, container: Container, r_max):
    if container.kind == "cylinder":
        keep = np.hypot(pts[:, 0], pts[:, 1]) <= container.radius - 1.05 * r_max
        pts = pts[keep]
    if container.kind == "hele-shaw":  # a point source's disk of sites reaches past the plates
        inside_x = np.abs(pts[:, 0]) <= 0.5 * container.size_x - 1.05 * r_max
        keep = inside_x & (np.abs(pts[:, 1]) <= 0.5 * container.gap - 1.05 * r_max + 1e-12)
        if not np.any(keep):  # a gap narrower than the lattice spacing: the sites on the mid-plane
            keep = inside_x & (np.abs(pts[:, 1]) < 1e-12)
        pts = pts[keep]
    if len(pts) == 0:
        raise PourFailure("pour: no lattice site fits the source inside the container")
    return pts


def initial_lattice(radius, container: Container, scene: dict, seed: int, hold_base: float, max_batches: int):
    """Lattice positions (N, 3) for grains in id order, and the batches as (first, last) index pairs."""
    rng = np.random.default_rng(seed)
    r_max = float(np.max(radius))
    spacing = 2.2 * r_max
    sites = _footprint_sites(container, scene, spacing, r_max, rng)
    n = len(radius)
    per_layer = len(sites)
    n_layers = int(math.ceil(n / per_layer))
    layers_per_batch = max(1, int(math.ceil(n_layers / max_batches)))
    pos = np.zeros((n, 3))
    jitter = 0.04 * spacing
    for k in range(n):
        layer, slot = divmod(k, per_layer)
        if slot == 0:
            order = rng.permutation(per_layer)  # which sites a partial top layer fills
        x, y = sites[order[slot]]
        pos[k, 0] = x + rng.uniform(-jitter, jitter)
        pos[k, 1] = (y + rng.uniform(-jitter, jitter)) if container.dimension == 3 else 0.0
        pos[k, 2] = hold_base + layer * spacing + rng.uniform(-jitter, jitter)
    if container.kind == "periodic":
        for axis, length in ((0, container.size_x), (1, container.size_y)):
            if length > 0 and (axis == 0 or container.dimension == 3):
                pos[:, axis] = np.mod(pos[:, axis] + 0.5 * length, length) - 0.5 * length
    batches = []
    per_batch = per_layer * layers_per_batch
    for first in range(0, n, per_batch):
        batches.append((first, min(n, first + per_batch) - 1))
    return pos, batches, {"sites_per_layer": per_layer, "layers": n_layers, "layers_per_batch": layers_per_batch,
                          "spacing": spacing}


def _wall_fixes(container: Container, models: str, wall_type: int) -> list:
    w = f"wall/gran {models} primitive type {wall_type}"
    lines = [f"fix floor all {w} zplane 0.0"]
    if container.kind in ("box", "hele-shaw"):
        hx = 0.5 * container.size_x
        lines += [f"fix wx1 all {w} xplane {-hx:.17g}", f"fix wx2 all {w} xplane {hx:.17g}"]
        if container.kind == "box" and container.dimension == 3:
            hy = 0.5 * container.size_y
            lines += [f"fix wy1 all {w} yplane {-hy:.17g}", f"fix wy2 all {w} yplane {hy:.17g}"]
        if container.kind == "hele-shaw":
            hy = 0.5 * container.gap
            lines += [f"fix wy1 all {w} yplane {-hy:.17g}", f"fix wy2 all {w} yplane {hy:.17g}"]
    if container.kind == "cylinder":
        lines.append(f"fix wcyl all {w} zcylinder {container.radius:.17g} 0.0 0.0")
    return lines


def open_region(pos, radius, scene: dict):
    """(lo, hi): lateral (x, y) bounds of an open floor's region, as btr relax sets them: the extents of
    the grains (pos, radius) grown by relax.open_margin (default 10) largest diameters."""
    margin_d = float((scene.get("relax") or {}).get("open_margin", 10.0))
    if not margin_d > 0:
        raise PourFailure(f"pour: scene relax.open_margin: expected a positive number, got {margin_d!r}")
    r = np.asarray(radius)[:, None]
    grow = margin_d * 2.0 * float(np.max(radius))
    lo = np.min(pos[:, :2] - r, axis=0) - grow
    hi = np.max(pos[:, :2] + r, axis=0) + grow
    return lo, hi


def _domain(container: Container, pos, radius, region=None):
    """(boundary string, xlo, xhi, ylo, yhi, zlo, zhi) of the simulation box; region: an open floor's
    lateral bounds (open_region)."""
    r_max = float(np.max(radius))
    pad = 2.0 * r_max
    zhi = float(np.max(pos[:, 2])) + 4.0 * r_max
    zlo = -pad
    if container.kind == "periodic":
        hx = 0.5 * container.size_x
        if container.dimension == 3:
            hy = 0.5 * container.size_y
            return "p p f", -hx, hx, -hy, hy, zlo, zhi
        return "p f f", -hx, hx, -pad, pad, zlo, zhi
    if container.kind in ("box", "hele-shaw"):
        hx = 0.5 * container.size_x + pad
        hy = (0.5 * container.size_y if container.kind == "box" else 0.5 * container.gap) + pad
        if container.dimension == 2:
            hy = pad
        return "f f f", -hx, hx, -hy, hy, zlo, zhi
    if container.kind == "cylinder":
        h = container.radius + pad
        return "f f f", -h, h, -h, h, zlo, zhi
    # open floor: fixed at the removal region (a grain leaving it is lost, i.e. removed, and counted)
    lo, hi = region
    if container.dimension == 2:
        return "f f f", lo[0], hi[0], -pad, pad, zlo, zhi
    return "f f f", lo[0], hi[0], lo[1], hi[1], zlo, zhi


def write_inputs(workdir: Path, radius, species, container: Container, scene: dict, settings: PourSettings,
                 btr_top: float, btr_pos=None):
    """Writes workdir/pour.data and workdir/in.pour; returns a dict of the numbers used. btr_pos: the BTR
    packing's positions, whose footprint bounds an open floor's region with the lattice's."""
    relax = scene.get("relax") or {}
    model = relax.get("model", "hertz")
    if model not in ("hertz", "hooke", "hooke-stiffness"):
        raise PourFailure(f"pour: scene relax.model: expected hertz, hooke or hooke-stiffness, got {model!r}")
    fraction = settings.timestep_fraction or float(relax.get("timestep_fraction", 0.2))
    dt, rule = dem_params.stable_timestep(radius, species, scene, fraction)
    if relax.get("timestep") and not settings.timestep_fraction:  # the scene's explicit step, as btr relax takes it
        if float(relax["timestep"]) > dt / fraction:
            raise PourFailure(f"pour: scene relax.timestep {relax['timestep']:g} s exceeds the contact time "
                              f"{dt / fraction:.4g} s ({rule})")
        dt, rule = float(relax["timestep"]), f"the scene's relax.timestep (stability rule: {rule})"
    stop_ratio = settings.stop_ratio if settings.stop_ratio is not None else float(relax.get("stop_kinetic_ratio", 1e-6))
    settle_max = settings.settle_max_time if settings.settle_max_time is not None else float(relax.get("max_time", 0.2))
    table = dem_params.species_table(scene)
    types = sorted(table)
    type_of = {s: k + 1 for k, s in enumerate(types)}
    wall_type = len(types) + 1  # walls: the first component's material, as the coupling does
    first_species = int(dem_params.components(scene)[0]["species"])
    d_mean = 2.0 * float(np.mean(radius))
    r_max = float(np.max(radius))
    hold_base = max(btr_top, 2 * r_max) * 1.5 + 6.0 * r_max
    pos, batches, lattice = initial_lattice(radius, container, scene, settings.seed, hold_base, settings.max_batches)
    gap = settings.drop_gap_d * d_mean

    # ---- data file ----
    region = None
    if container.kind == "open":
        pts, rs = (pos, radius) if btr_pos is None else (np.vstack([pos, btr_pos]), np.concatenate([radius, radius]))
        region = open_region(pts, rs, scene)
    boundary, xlo, xhi, ylo, yhi, zlo, zhi = _domain(container, pos, radius, region)
    rows = [f"LIGGGHTS data file written by btrdem.dem.pour (seed {settings.seed})", "",
            f"{len(radius)} atoms", f"{len(types) + 1} atom types", "",
            f"{xlo:.17g} {xhi:.17g} xlo xhi", f"{ylo:.17g} {yhi:.17g} ylo yhi", f"{zlo:.17g} {zhi:.17g} zlo zhi", "",
            "Atoms", ""]
    for k in range(len(radius)):
        s = int(species[k])
        rows.append(f"{k + 1} {type_of[s]} {2 * radius[k]:.17g} {table[s]['density']:.17g} "
                    f"{pos[k, 0]:.17g} {pos[k, 1]:.17g} {pos[k, 2]:.17g}")
    atomic_write_text(workdir / "pour.data", "\n".join(rows) + "\n")

    # ---- input script ----
    # Types 1..K are the species (sorted), type K+1 the walls. Unlike species take the mean of
    # restitution and friction; a grain-wall contact takes the grain's value (coupling/dem/materials.h).
    mats = [table[s] for s in types] + [table[first_species]]
    nt = len(mats)

    def per_type(key):
        return " ".join(f"{m[key]:.17g}" for m in mats)

    def per_pair(key):
        vals = []
        for i in range(nt):
            for j in range(nt):
                a, b = mats[i][key], mats[j][key]
                v = a if j == nt - 1 else b if i == nt - 1 else 0.5 * (a + b)
                vals.append(f"{v:.17g}")
        return " ".join(vals)

    rolling = any(m["rolling_friction"] > 0 for m in mats)
    models = f"model {'hooke/stiffness' if model == 'hooke-stiffness' else model} tangential history" + (" rolling_friction epsd2" if rolling else "")
    threshold = dem_params.kinetic_threshold(radius, species, scene, stop_ratio)
    g = dem_params.G
    batch_steps = []
    for first, last in batches:
        thickness = float(pos[last, 2] - pos[first, 2]) + 2 * r_max
        t_fall = math.sqrt(2.0 * (gap + thickness) / g)
        batch_steps.append(max(1, int(math.ceil(settings.pace * t_fall / dt))))
    check_steps = max(1, int(round(settings.check_every / dt)))
    thermo_every = max(1, check_steps // 5)
    schedule_time = sum(batch_steps) * dt
    t_max = schedule_time + settle_max
    skin = 0.5 * float(np.min(radius))
    L = [
        "# Reference DEM pour written by btrdem.dem.pour (see workflows/btrdem/dem/pour.py for the method)",
        "atom_style granular", "atom_modify map array", f"boundary {boundary}", "newton off",
        "communicate single vel yes", "units si",
        "processors " + ("* 1 1" if container.dimension == 2 else "* * 1"), "read_data pour.data",
        f"neighbor {skin:.17g} bin", "neigh_modify delay 0",
        f"fix m1 all property/global youngsModulus peratomtype {per_type('young')}",
        f"fix m2 all property/global poissonsRatio peratomtype {per_type('poisson')}",
        f"fix m3 all property/global coefficientRestitution peratomtypepair {nt} {per_pair('restitution')}",
        f"fix m4 all property/global coefficientFriction peratomtypepair {nt} {per_pair('friction')}",
    ]
    young = [m["young"] for m in mats]
    if min(young) < 5e6:  # LIGGGHTS refuses moduli outside [5e6, 1e9] Pa unless told
        L.insert(L.index("read_data pour.data") + 1, "soft_particles yes")
    if max(young) > 1e9:
        L.insert(L.index("read_data pour.data") + 1, "hard_particles yes")
    if rolling:
        L.append(f"fix m6 all property/global coefficientRollingFriction peratomtypepair {nt} "
                 f"{per_pair('rolling_friction')}")
    if model == "hooke-stiffness":  # absolute_damping off: gamman, gammat are rates times m_eff
        for key, name in (("kn", "kn"), ("kt", "kt"), ("gamma_n", "gamman")):
            L.append(f"fix s_{name} all property/global {name} peratomtypepair {nt} {per_pair(key)}")
        vals = []
        for i in range(nt):
            for j in range(nt):
                a, b = mats[i], mats[j]
                v = (a["wall_gamma_t"] if j == nt - 1 else b["wall_gamma_t"] if i == nt - 1
                     else 0.5 * (a["gamma_t"] + b["gamma_t"]))
                vals.append(f"{v:.17g}")
        L.append(f"fix s_gammat all property/global gammat peratomtypepair {nt} {' '.join(vals)}")
    if model == "hooke":
        L.append("fix m5 all property/global characteristicVelocity scalar "
                 f"{dem_params.hooke_characteristic_velocity(radius):.17g}")
    L += [f"pair_style gran {models}", "pair_coeff * *", f"timestep {dt:.17g}",
          "fix gravi all gravity 9.81 vector 0.0 0.0 -1.0"]
    L += _wall_fixes(container, models, wall_type)
    if container.dimension == 2:
        L.append("fix plane all setforce NULL 0.0 NULL")
    L += ["compute ket all ke", "compute ker all erotate/sphere", "variable ke equal c_ket+c_ker",
          "variable t equal time", "variable na equal count(all)",
          f"variable thr equal {threshold:.17g}", f"variable tmax equal {t_max:.17g}",
          f"thermo_style custom step time atoms c_ket c_ker", f"thermo {thermo_every}",
          f"thermo_modify lost {'ignore' if region is not None else 'error'} norm no",
          f"fix kehist all print {thermo_every} \"${{t}} ${{ke}}\" file kinetic.txt screen no title \"# time ke\""]
    top_var = "variable top equal bound(released,zmax)"
    for k, (first, last) in enumerate(batches):
        a, b = first + 1, last + 1
        L.append(f"# batch {k + 1}/{len(batches)}: grains {a}..{b}")
        L.append(f"group b{k} id <> {a} {b}")
        L.append(f"variable lo equal bound(b{k},zmin)")
        if k == 0:
            L.append(f"variable dz equal {r_max + gap:.17g}-v_lo")
        else:
            L.append(f"variable dz equal v_top+{2 * r_max + gap:.17g}-v_lo")
        L.append(f"displace_atoms b{k} move 0 0 ${{dz}} units box")
        L.append(f"group released id <> 1 {b}")
        if k == 0:
            L.append(top_var)
            L.append("fix integr released nve/sphere")
        L.append(f"group b{k} delete")
        L.append(f"print \"BTR_BATCH {k + 1} {len(batches)}\"")
        L.append(f"run {batch_steps[k]}")
    L += ["label settle", f"run {check_steps}",
          "if \"${ke} < ${thr}\" then \"print 'BTR_STOP kinetic-energy'\" \"jump SELF done\"",
          "if \"${t} >= ${tmax}\" then \"print 'BTR_STOP max-time'\" \"jump SELF done\"",
          "jump SELF settle", "label done",
          "print \"BTR_FINAL ${t} ${ke} ${na}\"",
          "write_dump all custom final.dump id x y z radius vx vy vz modify sort id"]
    atomic_write_text(workdir / "in.pour", "\n".join(L) + "\n")
    return {"timestep": dt, "timestep_rule": rule, "model": model, "kinetic_threshold": threshold,
            "stop_ratio": stop_ratio, "settle_max_time": settle_max, "schedule_time": schedule_time,
            "batches": len(batches), "batch_steps": batch_steps, "drop_gap": gap, "hold_base": hold_base,
            "lattice": lattice, "open_region": None if region is None else
                {"x": [float(region[0][0]), float(region[1][0])], "y": [float(region[0][1]), float(region[1][1])]},
            "initial_potential_energy":
                float(np.sum(dem_params.masses(radius, species, scene) * g * pos[:, 2]))}


def read_dump(path: Path, n: int, may_lose: bool = False):
    """Columns of a LIGGGHTS dump of n grains (fewer allowed with may_lose: an open floor's removed grains)."""
    with open(path) as f:
        lines = f.read().splitlines()
    try:
        start = next(k for k, line in enumerate(lines) if line.startswith("ITEM: ATOMS"))
    except StopIteration:
        raise PourFailure(f"{path}: no ITEM: ATOMS section") from None
    cols = lines[start].split()[2:]
    data = np.array([[float(v) for v in line.split()] for line in lines[start + 1:] if line.strip()])
    if data.shape[0] != n and not (may_lose and data.shape[0] <= n):
        raise PourFailure(f"{path}: expected {n} grains, got {data.shape[0]} (grains lost)")
    return {c: data[:, k] for k, c in enumerate(cols)}


def _pour_status(log: Path) -> str:
    """'batch k/n, t = ... s' from the end of the LIGGGHTS log, for progress lines."""
    try:
        with open(log, "rb") as f:
            f.seek(0, os.SEEK_END)
            f.seek(max(0, f.tell() - 65536))
            lines = f.read().decode(errors="replace").splitlines()
    except OSError:
        return ""
    batch = next((line.split()[1:3] for line in reversed(lines) if line.startswith("BTR_BATCH")), None)
    t = None
    for line in reversed(lines):
        parts = line.split()
        if len(parts) >= 4 and parts[0].isdigit():
            t = parts[1]
            break
    where = f"batch {batch[0]}/{batch[1]}" if batch else "starting"
    if batch and batch[0] == batch[1] and "label settle" not in lines:
        where += " (or settling)"
    return where + (f", t = {float(t):.3g} s" if t else "")


def _log_marks(log: Path):
    stop, final = None, None
    try:
        for line in open(log, errors="replace"):
            if line.startswith("BTR_STOP"):
                stop = line.split()[1]
            elif line.startswith("BTR_FINAL"):
                final = [float(x) for x in line.split()[1:4]]
    except OSError:
        pass
    return stop, final


def pour(btr: Packing, outdir: str | os.PathLike, settings: PourSettings = PourSettings(), progress=print,
         name: str = "poured") -> dict:
    """Pours btr's grains in LIGGGHTS into outdir; writes outdir/NAME.{csv,json,vtp}, kinetic.csv,
    in.pour, pour.data, log.liggghts. Returns a summary dict (wall time, stop reason, ...)."""
    scene = btr.scene()
    if not scene:
        raise PourFailure(f"{btr.path}: the packing JSON holds no scene; the pour needs it")
    container = btr.container()
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    top = float(np.max(btr.pos[:, 2] + btr.radius))
    plan = write_inputs(out, btr.radius, btr.species, container, scene, settings, top, btr.pos)
    progress(f"  [{settings.label}] {len(btr)} grains, {plan['batches']} batches, dt = {plan['timestep']:.3g} s, "
             f"schedule {plan['schedule_time']:.3g} s + settling <= {plan['settle_max_time']:.3g} s")
    argv = ["liggghts", "-in", "in.pour", "-log", "log.liggghts", "-screen", "none", "-echo", "none"]
    env = {}
    if settings.np > 1:
        argv = ["mpirun", "-np", str(settings.np)] + argv
        if os.geteuid() == 0:
            env = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
    if shutil.which(argv[0]) is None:
        raise PourFailure(f"pour: {argv[0]} not found on PATH (Debian package liggghts / openmpi-bin)")
    res = run_command(argv, out, settings.label, progress=progress, env=env, watch=str(out / "log.liggghts"),
                      timeout=settings.wall_time_limit, status=lambda: _pour_status(out / "log.liggghts"))
    log = out / "log.liggghts"
    if res["returncode"] != 0:
        tail = "".join(open(log, errors="replace").readlines()[-12:]) if log.exists() else ""
        raise PourFailure(f"{settings.label}: LIGGGHTS exited with status {res['returncode']} "
                          f"(see {log})\n{tail.rstrip()}")
    stop, final = _log_marks(log)
    if stop is None:
        raise PourFailure(f"{settings.label}: LIGGGHTS finished without a stop mark (see {log})")
    dump = read_dump(out / "final.dump", len(btr), may_lose=container.kind == "open")
    xyz = np.column_stack([dump["x"], dump["y"], dump["z"]])
    if not np.all(np.isfinite(xyz)):
        raise PourFailure(f"{settings.label}: NaN positions in {out / 'final.dump'}")
    ids = dump["id"].astype(np.int64)
    kept = ids - 1  # indices into btr's grains
    if not (np.all(np.diff(ids) > 0) and len(ids) and ids[0] >= 1 and ids[-1] <= len(btr)) or (
            container.kind != "open" and len(ids) != len(btr)):
        raise PourFailure(f"{settings.label}: {out / 'final.dump'}: ids are not 1..{len(btr)}")
    removed_ids = np.setdiff1d(np.arange(1, len(btr) + 1), ids)
    ids = np.arange(1, len(ids) + 1)
    if container.dimension == 2:
        xyz[:, 1] = 0.0
    kin = np.loadtxt(out / "kinetic.txt", comments="#", ndmin=2) if (out / "kinetic.txt").exists() else np.zeros((0, 2))
    atomic_write_text(out / "kinetic.csv", "time,kinetic_energy\n" +
                      "".join(f"{t:.9g},{e:.9g}\n" for t, e in kin[:, :2]))
    if len(kin) and np.max(kin[:, 1]) > 10.0 * plan["initial_potential_energy"]:
        raise PourFailure(f"{settings.label}: kinetic energy {np.max(kin[:, 1]):.3g} J exceeds ten times the "
                          f"initial potential energy {plan['initial_potential_energy']:.3g} J (blow-up)")
    tol = 0.5 * btr.radius[kept]
    low = xyz[:, 2] < -tol
    walls = container.wall_distance(xyz) < -tol if container.has_walls() else np.zeros(len(xyz), bool)
    if np.any(low | walls):
        k = int(np.nonzero(low | walls)[0][0])
        raise PourFailure(f"{settings.label}: grain {k + 1} left the container (at {xyz[k].tolist()})")
    meta = {"scene": scene, "seed": settings.seed, "dimension": container.dimension,
            "container": scene.get("container"), "source_packing": os.path.abspath(btr.path),
            "method": "liggghts pour (btrdem.dem.pour)", "pour": dict(asdict(settings), **plan),
            "stop_reason": stop, "simulated_time": final[0] if final else None,
            "final_kinetic_energy": final[1] if final else None,
            "timings": {"pour_wall_seconds": res["wall_seconds"], "pour_cpu_seconds": res["cpu_seconds"]},
            "counts": {"grains": len(ids), "poured": len(btr)}}
    if plan["open_region"] is not None:
        meta["removed"] = {"count": int(len(removed_ids)), "ids": removed_ids.tolist(), "region": plan["open_region"],
                           "rule": "grains whose centre left the region (the footprint + relax.open_margin largest "
                                   "diameters) were removed; ids are the BTR packing's; the others are renumbered"}
    poured = Packing(ids=ids, pos=xyz, radius=dump["radius"], species=btr.species[kept].copy(), meta=meta,
                     path=str(out / f"{name}.csv"))
    if not np.allclose(poured.radius, btr.radius[kept], rtol=1e-6):
        raise PourFailure(f"{settings.label}: radii in final.dump differ from the BTR packing's")
    poured.radius = btr.radius[kept].copy()
    write_packing(out, name, poured)
    summary = {"wall_seconds": res["wall_seconds"], "cpu_seconds": res["cpu_seconds"], "stop_reason": stop, "simulated_time": meta["simulated_time"],
               "timestep": plan["timestep"], "batches": plan["batches"], "packing": str(out / f"{name}.csv"),
               "seed": settings.seed, "removed": int(len(removed_ids))}
    write_json(out / "pour_summary.json", summary)
    progress(f"  [{settings.label}] done in {res['wall_seconds']:.1f} s wall ({res['cpu_seconds']:.1f} s CPU), "
             f"{meta['simulated_time']:.3g} s "
             f"simulated, stop: {stop}" + (f"; {len(removed_ids)} grain(s) left the open floor's region, removed"
                                            if len(removed_ids) else ""))
    return summary


_REUSE_KEYS = ("seed", "pace", "stop_ratio", "drop_gap_d", "max_batches", "settle_max_time", "timestep_fraction")


def finished_pour(btr: Packing, outdir: str | os.PathLike, settings: PourSettings, name: str = "poured") -> dict | None:
    """The summary of a pour already finished in outdir with the same settings and the same grains (radii
    equal to btr's, in order), or None. Its wall time is the one recorded when it ran; the summary says
    so ("reused": true)."""
    out = Path(outdir)
    summary_path, meta_path, csv = out / "pour_summary.json", out / f"{name}.json", out / f"{name}.csv"
    if not (summary_path.exists() and meta_path.exists() and csv.exists()):
        return None
    summary, meta = read_json(summary_path), read_json(meta_path)
    ran = meta.get("pour", {})
    # None in settings means "the scene's value", which the meta records resolved: compare only what was set.
    if any(getattr(settings, k) is not None and ran.get(k) != getattr(settings, k) for k in _REUSE_KEYS):
        return None
    poured = read_packing(str(csv))
    removed = np.asarray((meta.get("removed") or {}).get("ids", []), dtype=np.int64)
    kept = np.setdiff1d(np.arange(1, len(btr) + 1), removed) - 1
    if len(poured) != len(kept) or not np.allclose(poured.radius, btr.radius[kept], rtol=1e-12, atol=0.0):
        return None
    return dict(summary, reused=True)
