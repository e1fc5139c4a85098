# The Python half of every YADE relaxation script: reading the packing, walls, contact laws, the run loop with
# its stop rule and failure checks, and the output files. coupling/yade/yade_script.cpp writes a header before
# it and the scene-specific calls (numbers, materials, pairs, grains, walls) after it; the build embeds this
# file into the btr program (coupling/CMakeLists.txt), so a script btr writes is whole on its own.
import json
import math
import os
import sys
import tempfile
import time
import traceback

# Everything is read from and written to the folder holding this script, wherever it is run from
# (`yade -x` runs scripts with __file__ pointing to the launcher, hence argv[0]).
HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
STATUS_FILE = "yade_status.json"
FINAL_FILE = "yade_final.csv"
KINETIC_FILE = "yade_kinetic.csv"
CONTACTS_FILE = "yade_contacts.csv"
TAPS_FILE = "yade_taps.json"  # tapping (TAP): one record per tap, rewritten after each
LOG_FILE = "yade.log"


class RunFailure(Exception):
    def __init__(self, message, kind="engine_error"):  # kind: a FailureKind name (coupling/dem/relax.h)
        Exception.__init__(self, message)
        self.kind = kind


def path(name):
    return os.path.join(HERE, name)


_log = None


def log(message):
    global _log
    if _log is None:
        _log = open(path(LOG_FILE), "w")
    print(message, flush=True)
    _log.write(message + "\n")
    _log.flush()


def write_atomically(name, text):
    # A unique temporary name: two runs writing into one folder never share it.
    fd, tmp = tempfile.mkstemp(prefix="." + name + ".", suffix=".tmp", dir=path("."))
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path(name))
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


# Stale outputs of an earlier run must never be mistaken for this run's.
for _name in (STATUS_FILE, FINAL_FILE, KINETIC_FILE, CONTACTS_FILE, TAPS_FILE):
    if os.path.exists(path(_name)):
        os.remove(path(_name))

try:
    import yade
    from yade import O, Vector3, utils
    from yade.wrapper import (Bo1_Box_Aabb, Bo1_Facet_Aabb, Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter,
                              FrictMat, Ig2_Box_Sphere_ScGeom, Ig2_Facet_Sphere_ScGeom, Ig2_Sphere_Sphere_ScGeom,
                              Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                              Ip2_FrictMat_FrictMat_MindlinPhys, Ip2_ViscElMat_ViscElMat_ViscElPhys,
                              Law2_ScGeom_MindlinPhys_Mindlin, Law2_ScGeom_ViscElPhys_Basic, MatchMaker,
                              NewtonIntegrator, PyRunner, ViscElMat)
except ImportError as exc:
    log("cannot import yade (%s): run with PYTHONPATH=/usr/lib/x86_64-linux-gnu/yade-double/py, "
        "or with `yade -n -x %s`" % (exc, os.path.basename(sys.argv[0])))
    write_atomically(STATUS_FILE, json.dumps({"status": "failed", "message": "cannot import yade: %s" % exc}) + "\n")
    sys.exit(2)

# Scene state filled by the generated calls of scene() below.
_materials = {}      # label -> material id
_species = {}        # species -> material id
_pairs = []          # (material id, material id, restitution, friction)
_material_args = {}  # material id -> (label, young, poisson, density): what a slab twin copies
_twins = {}          # a species' material id -> its twin's (a compaction in slabs; twin_materials())
_grains = []         # [(packing id, body id)] in packing order
_walls = []          # body ids of walls, facets and the periodic floor
_floor = None        # body id of the floor (the plane wall or periodic floor box at z = 0), which TAP moves
_clumps = []         # body ids of the clumps (rigid clusters), one per cluster of the packing
_cell = None         # (Lx, Ly, Lz) when periodic
_rolling = None      # dict(krot=, eta=) for the Hertz-Mindlin moment law; None = no rolling term
_removed = []        # packing ids of grains removed because they left REGION (open floor), in removal order
_history = []        # [(time, translational kinetic energy)] at t = 0 and at every check
_loop_seconds = 0.0  # wall time of the time-stepping loop alone


def add_material(label, young, poisson, density, species=None):
    """Elastic constants and density; restitution and friction are per pair (pair())."""
    if MODEL == "hertz":
        mat = FrictMat(young=young, poisson=poisson, frictionAngle=0.0, density=density, label=label)
    else:
        # ViscElMat with young and en: kn = 1 / (1/(2 E1 r1) + 1/(2 E2 r2)), ks = poisson * kn (here
        # `poisson` is the ratio ks/kn), normal dashpot from the pair's restitution; en is a placeholder
        # overridden by the Ip2 functor's MatchMaker.
        mat = ViscElMat(young=young, poisson=poisson, en=1.0, frictionAngle=0.0, density=density, label=label)
    mid = O.materials.append(mat)
    _materials[label] = mid
    _material_args[mid] = (label, young, poisson, density)
    if species is not None:
        _species[species] = mid


def pair(label_a, label_b, restitution, friction):
    _pairs.append((_materials[label_a], _materials[label_b], restitution, friction))


def set_rolling(krot, eta):
    global _rolling
    _rolling = dict(krot=krot, eta=eta)


def periodic_cell(lx, ly, lz):
    global _cell
    O.periodic = True
    O.cell.setBox(lx, ly, lz)
    _cell = (lx, ly, lz)


def add_grains(csv_name):
    """The grains of the packing: id,x,y,z,radius,species[,cluster]. Grains of one cluster (cluster > 0) become
    one clump (O.bodies.appendClumped): a rigid body whose members keep their relative positions; YADE makes
    no contact between members of one clump. In a periodic cell btr writes a cluster's members unwrapped
    (together, possibly outside the cell); write_outputs wraps every grain into the cell again. Every grain
    keeps its packing id (_grains maps it to its body)."""
    free = []      # (packing id, body)
    clusters = {}  # cluster -> [(packing id, body)]
    with open(path(csv_name)) as f:
        header = f.readline().strip()
        with_clusters = header == "id,x,y,z,radius,species,cluster"
        if header != "id,x,y,z,radius,species" and not with_clusters:
            raise RunFailure("%s: header is %r, expected 'id,x,y,z,radius,species[,cluster]'" % (csv_name, header))
        expected = header
        count = 0
        for n, line in enumerate(f, start=2):
            if not line.strip():
                continue
            try:
                fields = line.split(",")
                if len(fields) != (7 if with_clusters else 6):
                    raise ValueError()
                gid, x, y, z, r, sp = int(fields[0]), float(fields[1]), float(fields[2]), float(fields[3]), \
                    float(fields[4]), int(fields[5])
                cluster = int(fields[6]) if with_clusters else 0
            except ValueError:
                raise RunFailure("%s line %d: expected %s, got %r" % (csv_name, n, expected, line.strip()))
            if gid != count + 1:
                raise RunFailure("%s line %d: id %d, expected %d (ids are 1..N in order)" % (csv_name, n, gid, count + 1))
            count += 1
            if not all(math.isfinite(v) for v in (x, y, z, r)) or r <= 0.0 or cluster < 0:
                raise RunFailure("%s line %d: non-finite value, radius <= 0 or cluster < 0" % (csv_name, n))
            if sp not in _species:
                raise RunFailure("%s line %d: species %d has no material" % (csv_name, n, sp))
            b = utils.sphere((x, y, z), r, material=_species[sp], color=(0.8, 0.6, 0.2))
            if cluster == 0:
                free.append((gid, b))
            else:
                clusters.setdefault(cluster, []).append((gid, b))
    if count == 0:
        raise RunFailure("%s has no grains" % csv_name)
    body_of = {}
    for gid, bid in zip((g for g, _ in free), O.bodies.append([b for _, b in free])):
        body_of[gid] = bid
        if DIMENSION == 2:
            # Disks in the x-z plane: no motion along y, rotation about y only.
            O.bodies[bid].state.blockedDOFs = "yXZ"
    for cluster in sorted(clusters):
        members = clusters[cluster]
        clump, member_ids = O.bodies.appendClumped([b for _, b in members])
        _clumps.append(clump)
        if DIMENSION == 2:
            O.bodies[clump].state.blockedDOFs = "yXZ"  # the clump is what NewtonIntegrator moves
        body_of.update(zip((g for g, _ in members), member_ids))
    _grains.extend((gid, body_of[gid]) for gid in range(1, count + 1))


def add_plane(axis, position):
    """An infinite plane wall. In a periodic cell YADE's collider cannot bound an infinite Wall, so the
    floor is a thin box whose top face is the plane, wider than the cell (allowBiggerThanPeriod)."""
    if _cell is not None:
        if axis != 2:
            raise RunFailure("a periodic cell has no side walls")
        t = 0.5 * min(_cell[0], _cell[1])
        half = (1000.0 * _cell[0], 1000.0 * _cell[1], 0.5 * t)
        b = utils.box((0.0, 0.0, position - 0.5 * t), half, fixed=True, material=_materials["walls"])
    else:
        b = utils.wall(position, axis=axis, material=_materials["walls"])
    _walls.append(O.bodies.append(b))
    if axis == 2:
        global _floor
        _floor = _walls[-1]


def add_cylinder(radius, height, segments):
    """Inner surface of a vertical cylinder about the z axis, from z = 0 to height, as `segments` flat panels
    (2 facets each) whose faces are tangent to the true cylinder: vertices at radius / cos(pi / segments), so
    a grain touching the container's cylinder touches a panel without overlap; at a panel edge the gap to
    the true surface is radius * (1 / cos(pi / segments) - 1)."""
    rv = radius / math.cos(math.pi / segments)
    facets = []
    for k in range(segments):
        a0 = 2.0 * math.pi * k / segments
        a1 = 2.0 * math.pi * (k + 1) / segments
        p0 = (rv * math.cos(a0), rv * math.sin(a0))
        p1 = (rv * math.cos(a1), rv * math.sin(a1))
        v00, v10 = (p0[0], p0[1], 0.0), (p1[0], p1[1], 0.0)
        v01, v11 = (p0[0], p0[1], height), (p1[0], p1[1], height)
        for tri in ((v00, v10, v11), (v00, v11, v01)):
            facets.append(utils.facet(tri, material=_materials["walls"], color=(0.5, 0.5, 0.5)))
    _walls.extend(O.bodies.append(facets))


def add_mesh(stl_name):
    """A mesh container's triangles as fixed facets (ymport.stl), from the ASCII STL file btr wrote beside
    this script in the packing's coordinates (scaled and placed as the scene says: no scale or shift here)."""
    from yade import ymport
    facets = ymport.stl(path(stl_name), material=_materials["walls"], color=(0.5, 0.5, 0.5))
    if not facets:
        raise RunFailure("the mesh file %s has no facets" % stl_name)
    _walls.extend(O.bodies.append(facets))


def twin_materials():
    """A compaction in slabs: each species' material gets a twin, the same material under another id, which the
    grains of the slab being compacted take (the LIGGGHTS script's twin types)."""
    for mid in sorted(set(_species.values())):
        label, young, poisson, density = _material_args[mid]
        add_material(label + "_twin", young, poisson, density)
        _twins[mid] = _materials[label + "_twin"]


def pair_values(scale):
    """(material id, material id, restitution, friction) of every pair the Ip2 functors may meet: friction scaled
    by `scale` for every pair, or, with slab twins, only for the pairs with a twin (a slab grain against anything);
    the others keep the scene's."""
    if not _twins:
        return [(a, b, e, mu * scale) for a, b, e, mu in _pairs]
    out = []
    for a, b, e, mu in _pairs:
        for ta in (a, _twins.get(a)):
            for tb in (b, _twins.get(b)):
                if ta is not None and tb is not None:
                    out.append((ta, tb, e, mu if (ta, tb) == (a, b) else mu * scale))
    return out


def friction_angles(scale):
    """The Ip2 functors' friction angles of every material pair, friction scaled by `scale` (pair_values)."""
    return MatchMaker(matches=[(a, b, math.atan(mu)) for a, b, _, mu in pair_values(scale)])


_ip2 = None  # the Ip2 functor (its frictAngle is replaced when the compaction restores the friction)
_collider = None  # the collider (a pour's release re-sorts it after moving a batch)


def build_engines():
    global _ip2, _collider
    if COMPACTION and COMPACTION.get("slabs"):
        twin_materials()
    en = MatchMaker(matches=[(a, b, e) for a, b, e, _ in pair_values(1.0)])
    friction_angle = friction_angles(COMPACTION["friction_scales"][0] if COMPACTION else 1.0)
    if MODEL == "hertz":
        ip2 = Ip2_FrictMat_FrictMat_MindlinPhys(en=en, frictAngle=friction_angle)
        law = Law2_ScGeom_MindlinPhys_Mindlin()
        if _rolling is not None:
            ip2.krot = _rolling["krot"]
            ip2.ktwist = 0.0
            ip2.eta = _rolling["eta"]
            law.includeMoment = True
    else:
        ip2 = Ip2_ViscElMat_ViscElMat_ViscElPhys(en=en, frictAngle=friction_angle)
        law = Law2_ScGeom_ViscElPhys_Basic()
    if _rolling is not None and COMPACTION:
        raise RunFailure("the compaction to a target packing fraction does not scale YADE's rolling friction")
    _ip2 = ip2
    collider = InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb(), Bo1_Facet_Aabb(), Bo1_Box_Aabb()],
                                     verletDist=VERLET_DIST, label="collider")
    if _cell is not None:
        # The floor box is wider than the cell: sweep along z, where it is thin.
        collider.allowBiggerThanPeriod = True
        collider.sortAxis = 2
        # Every run finds every pair whose boxes overlap (a sweep along z), not only the boxes that crossed since
        # the last run: YADE 2023.02's incremental periodic sort let two grains whose boxes both straddled the
        # cell's boundary pass into each other with no interaction (a pour, overlap 1.39 r; coupling/README.md).
        collider.sortThenCollide = True
        # A relaxation's boxes keep the whole margin, so that the search runs rarely: by default (targetInterv 100)
        # a slow grain's box shrinks to the distance it would cover in 100 steps, and a bed near rest outgrew some
        # box every few steps (954 full searches in a 10^4-grain settle, 58 % of its time; 18 with the whole
        # margin). A pour keeps the default: its falling grains run the search often anyway, and the pile's small
        # boxes save pairs (coupling/README.md).
        if not POUR:
            collider.targetInterv = 0
    _collider = collider
    O.engines = [
        ForceResetter(),
        collider,
        InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom(), Ig2_Facet_Sphere_ScGeom(),
                         Ig2_Box_Sphere_ScGeom()], [ip2], [law]),
        # DAMPING is YADE's local non-viscous damping, off (0) unless the scene or `btr relax --damping` asks
        # for it: then, besides the contact dashpots and friction, each force component is reduced by
        # DAMPING |F| against the velocity. kinSplit + O.trackEnergy give the translational kinetic energy.
        NewtonIntegrator(gravity=(0.0, 0.0, -GRAVITY), damping=COMPACTION["damping"] if COMPACTION else DAMPING,
                         kinSplit=True, label="newton"),
    ]
    O.trackEnergy = True


def translational_kinetic_energy():
    return O.energy["kinTrans"]


def wrap(x, length):
    return x - length * math.floor(x / length + 0.5)


def write_history():
    lines = ["time,kinetic_energy"] + ["%.17g,%.17g" % h for h in _history]
    write_atomically(KINETIC_FILE, "\n".join(lines) + "\n")


def write_outputs():
    write_history()
    lines = ["id,x,y,z,vx,vy,vz"]
    for gid, bid in _grains:
        b = O.bodies[bid]
        if b is None:  # removed (open floor)
            continue
        p, v = b.state.pos, b.state.vel
        x, y = p[0], p[1]
        if DIMENSION == 2 and b.isClumpMember and abs(y) < 1e-9 * b.shape.radius:
            # A clump member's position is its clump's rotated by a quaternion: round-off off the x-z
            # plane (~1e-16 r; the clump's DOFs out of the plane are blocked). A larger y is reported.
            y = 0.0
        if _cell is not None:
            x = wrap(x, _cell[0])
            if DIMENSION == 3:
                y = wrap(y, _cell[1])
        lines.append("%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g" % (gid, x, y, p[2], v[0], v[1], v[2]))
    write_atomically(FINAL_FILE, "\n".join(lines) + "\n")
    packing_id = {bid: gid for gid, bid in _grains}
    lines = ["i,j,fn,overlap"]
    # (removed grains are no longer bodies: their ids never appear here)
    for i in O.interactions:
        if not i.isReal or i.geom.penetrationDepth <= 0.0:
            continue
        a, b = packing_id.get(i.id1, 0), packing_id.get(i.id2, 0)
        if a == 0 or (b != 0 and b < a):
            a, b = b, a
        lines.append("%d,%d,%.17g,%.17g" % (a, b, i.phys.normalForce.norm(), i.geom.penetrationDepth))
    write_atomically(CONTACTS_FILE, "\n".join(lines) + "\n")


def write_status(status, reason, message, wall, kind=None):
    steps = O.iter
    write_atomically(STATUS_FILE, json.dumps({
        "status": status, "stop_reason": reason, "message": message, "failure_kind": kind,
        "time": O.time, "steps": steps, "timestep": O.dt, "wall_seconds": wall,
        "steps_per_second": steps / wall if wall > 0 else 0.0,
        "loop_seconds": _loop_seconds,
        "loop_steps_per_second": steps / _loop_seconds if _loop_seconds > 0 else 0.0,
        "grains": len(_grains), "clumps": len(_clumps), "bodies": len(O.bodies), "threads": O.numThreads,
        "yade_version": getattr(yade.config, "version", "unknown"), "model": MODEL,
        "stop_value": _rule.value if _rule is not None else None,
        "final_unbalanced_force": _final_unbalanced,
        "removed": _removed,
        "compaction": _rule.compaction.outcome if _rule is not None else None,
    }, indent=1) + "\n")


def unbalanced_force():
    """YADE's utils.unbalancedForce(): mean over grains of |contact forces + m g| / mean over contacts of
    |normal + shear force|; a large number while no contact carries force yet."""
    try:
        return utils.unbalancedForce()
    except (ZeroDivisionError, ArithmeticError):
        return float("inf")


def present_grains():
    """(packing id, body) of every grain still in the simulation (an open floor erases the ones that leave)."""
    for gid, bid in _grains:
        b = O.bodies[bid]
        if b is not None:
            yield gid, b


def remove_escaped():
    """Open floor: erases every grain whose centre left REGION (x0, x1, y0, y1); returns how many."""
    if REGION is None:
        return 0
    x0, x1, y0, y1 = REGION
    gone = [(gid, b.id) for gid, b in present_grains()
            if not (x0 <= b.state.pos[0] <= x1) or (DIMENSION == 3 and not (y0 <= b.state.pos[1] <= y1))]
    for gid, bid in gone:
        O.bodies.erase(bid)
        _removed.append(gid)
    return len(gone)


def grain_positions():
    return [O.bodies[bid].state.pos if O.bodies[bid] is not None else None for _, bid in _grains]


def grain_part_between(z, r, a, b):
    """Volume (area in 2D) of a sphere (disk) of centre height z and radius r between the planes a and b."""
    a, b = max(a, z - r), min(b, z + r)
    if b <= a:
        return 0.0
    if DIMENSION == 3:
        return math.pi * (r * r * (b - a) - ((b - z) ** 3 - (a - z) ** 3) / 3.0)
    ua, ub = (min(max((u - z) / r, -1.0), 1.0) for u in (a, b))
    return r * r * (ub * math.sqrt(1.0 - ub * ub) + math.asin(ub) - ua * math.sqrt(1.0 - ua * ua) - math.asin(ua))


def bulk_packing_fraction(z_window=None):
    """Solid fraction (area fraction in 2D) of COMPACTION's window (the LIGGGHTS script's variable btr_phi): each
    grain's part between its planes in z, times, in walled containers, its fraction between the side planes in x
    (and y in 3D): exact where one side cuts a grain, the product's approximation where two do. z_window: (z from,
    z to, measure) in place of the window's own (a slab's)."""
    c = COMPACTION
    lo, hi = c["window_lo"], c["window_hi"]
    z_lo, z_hi, measure = z_window if z_window else (lo[2], hi[2], c["window_measure"])
    solid = 0.0
    for _, b in present_grains():
        p, r = b.state.pos, b.shape.radius
        part = grain_part_between(p[2], r, z_lo, z_hi)
        if part and not c["slab"]:
            whole = grain_part_between(0.0, r, -r, r)
            part *= grain_part_between(p[0], r, lo[0], hi[0]) / whole
            if DIMENSION == 3:
                part *= grain_part_between(p[1], r, lo[1], hi[1]) / whole
        solid += part
    return solid / measure


class Compaction:
    """The compaction to COMPACTION["target"] (btr relax --target-phi; the LIGGGHTS script's, step for step):
    friction scaled by friction_scales[k], NewtonIntegrator damping COMPACTION["damping"], the bulk packing
    fraction checked at every sample; at the target, or when the last scale has brought the bed to rest (kinetic
    energy and its mean over STEPS_PER_CHECK steps below COMPACTION["rest_kinetic"], after the arming time of the
    scale) or used max_time, the friction of every pair and contact is restored, every grain stopped, DAMPING
    set, and the stop rule armed anew.
    In slabs (COMPACTION["slabs"], settle's deep beds): slab k's grains are released and take their twin
    material (frictionless against anything), the grains above are held (blockedDOFs "xyzXYZ", as a pour's
    lattice), and the same checks run on slab k's window; at its target, at rest or after max_time its grains
    take their material back, "BTR-COMPACTION-SLAB k K reached|rest|max-time ..." is logged and the next slab
    released; after the last, as above."""

    def __init__(self, rule):
        self.rule = rule
        self.active = bool(COMPACTION)
        self.k = 0
        self.samples = 0
        self.recent = []
        self.rest_from = COMPACTION["arming"] if COMPACTION else 0.0
        self.outcome = None
        self.slabs = COMPACTION.get("slabs") if COMPACTION else None
        self.slab = 0             # the slab being compacted
        self.slabs_reached = 0

    def start(self):
        """Before the first step: in slabs, every grain above the first slab held, the first released."""
        if not self.slabs:
            return
        for _, bid in _grains[self.slabs[0][1]:]:
            b = O.bodies[bid]
            b.state.blockedDOFs = "xyzXYZ"
            b.state.vel = Vector3(0.0, 0.0, 0.0)
            b.state.angVel = Vector3(0.0, 0.0, 0.0)
        log("compaction in %d slabs from the floor up: grains %d.. held" % (len(self.slabs), self.slabs[0][1] + 1))
        self.release_slab(0, 0.0)

    def slab_grains(self, k):
        first, last = self.slabs[k][:2]
        return [O.bodies[bid] for _, bid in _grains[first - 1:last] if O.bodies[bid] is not None]

    def release_slab(self, k, t):
        # The 2D grains keep their plane (add_grains' "yXZ"); `dynamic = True` would free every degree of freedom.
        free = "yXZ" if DIMENSION == 2 else ""
        for b in self.slab_grains(k):
            b.state.blockedDOFs = free
            b.material = O.materials[_twins[b.material.id]]
        self.set_friction(self.scale())
        self.slab, self.samples, self.recent, self.rest_from = k, 0, [], t + COMPACTION["arming"]
        first, last, lo, hi, _ = self.slabs[k]
        log("compaction: slab %d of %d (grains %d..%d) released at t = %.6g s, its pairs' friction x %g, window z "
            "%.6g..%.6g m" % (k + 1, len(self.slabs), first, last, t, self.scale(), lo, hi))

    def end_slab(self, how, t, phi):
        """Slab self.slab ends (how: reached, rest or max-time): its grains take their own material back, then the
        next slab is released or, after the last, the compaction finishes."""
        k, n = self.slab, len(self.slabs)
        log("BTR-COMPACTION-SLAB %d %d %s t = %.17g s phi = %.17g" % (k + 1, n, how, t, phi))
        self.slabs_reached += how == "reached"
        own = dict((twin, mid) for mid, twin in _twins.items())
        for b in self.slab_grains(k):
            b.material = O.materials[own[b.material.id]]
        if k + 1 < n:
            self.release_slab(k + 1, t)
        else:
            self.finish(self.slabs_reached == n, t, phi)

    def scale(self):
        return COMPACTION["friction_scales"][self.k]

    def step(self, t, e):
        """Called at every sample while active; returns True while the compaction goes on."""
        c = COMPACTION
        phi = bulk_packing_fraction(self.slabs[self.slab][2:] if self.slabs else None)
        if self.k == 0 and self.slab == 0 and self.samples == 0:
            log("compaction: first check at t = %.6g s, phi %.6g" % (t, phi))
        self.samples += 1
        self.recent = (self.recent + [e])[-(STEPS_PER_CHECK // AVERAGE_EVERY):]
        if phi >= c["target"]:
            if self.slabs:
                self.end_slab("reached", t, phi)
            else:
                self.finish(True, t, phi)
            return self.active
        at_rest = t >= self.rest_from and e < c["rest_kinetic"] and \
            sum(self.recent) / len(self.recent) < c["rest_kinetic"]
        if self.slabs and (at_rest or self.samples >= c["max_samples_per_scale"]):
            self.end_slab("rest" if at_rest else "max-time", t, phi)
            return self.active
        if at_rest or self.samples >= c["max_samples_per_scale"]:
            log("compaction: friction x %g at rest below the target at t = %.6g s, phi %.6g" % (self.scale(), t, phi))
            if self.k + 1 == len(c["friction_scales"]):
                self.finish(False, t, phi)
                return False
            self.k += 1
            self.samples = 0
            self.recent = []
            self.rest_from = t + c["arming"]
            self.set_friction(self.scale())
        return True

    def set_friction(self, scale):
        """The Ip2 functor's friction for new contacts and every existing contact's, by its bodies' materials."""
        _ip2.frictAngle = friction_angles(scale)
        tangent = {}
        for a, b, _, mu in pair_values(scale):
            tangent[(a, b)] = tangent[(b, a)] = mu
        for i in O.interactions:
            if i.isReal:
                i.phys.tangensOfFrictionAngle = tangent[(O.bodies[i.id1].material.id, O.bodies[i.id2].material.id)]

    def finish(self, reached, t, phi):
        scale = self.scale()
        log("compaction %s: friction x %g, t = %.6g s, phi %.6g; friction restored, grains stopped, damping %g" % (
            "reached the target" if reached else "did NOT reach the target", scale, t, phi, DAMPING))
        log("BTR-COMPACTION-END %s friction x %g t = %.17g s phi = %.17g" % (
            "reached" if reached else "not-reached", scale, t, phi))
        self.set_friction(1.0)
        for b in O.bodies:
            if b is not None and b.dynamic:
                b.state.vel = Vector3(0.0, 0.0, 0.0)
                b.state.angVel = Vector3(0.0, 0.0, 0.0)
        next(e for e in O.engines if isinstance(e, NewtonIntegrator)).damping = DAMPING
        O.dt = TIMESTEP
        self.outcome = {"reached": reached, "friction_scale": scale, "time": t, "packing_fraction": phi}
        self.active = False
        self.rule.rearm(t)


class StopRule:
    """The stop rules of the LIGGGHTS script, step for step, run inside YADE's loop by a PyRunner every
    AVERAGE_EVERY steps (so YADE runs whole chunks of steps without returning to Python): the translational
    kinetic energy E is sampled after every AVERAGE_EVERY-th step; every STEPS_PER_CHECK steps comes a check.
    STOP_RULE "kinetic-energy": E and the mean of the last STEPS_PER_CHECK / AVERAGE_EVERY samples are both
    below KINETIC_THRESHOLD, once armed (the mean was above it once, or t >= ARMING_TIME);
    "unbalanced-force": utils.unbalancedForce() < UNBALANCED_THRESHOLD, once t >= ARMING_TIME;
    "displacement": the largest grain displacement since the previous check < DISPLACEMENT_THRESHOLD [m],
    once t >= ARMING_TIME. Otherwise the run ends after MAX_CHECKS checks (max-time). A sample above
    KINETIC_BOUND is a blow-up. With an open floor (REGION), grains whose centre left the region are erased
    at every check (and counted).
    The PyRunner runs during a step, after NewtonIntegrator: that step ends at O.iter + 1, O.time + O.dt.
    It never raises (an exception would stop YADE with a bare "PyRunner error"): it records the reason or
    the failure and pauses the run."""

    def __init__(self):
        self.samples = STEPS_PER_CHECK // AVERAGE_EVERY
        self.total = 0.0
        self.count = 0
        self.checks = 0
        self.armed = False
        self.bodies = len(O.bodies)
        self.reason = None
        self.value = None
        self.failure = None
        self.next_report = time.time() + 10.0
        self.reference = grain_positions() if STOP_RULE == "displacement" else None
        self.arming_time = ARMING_TIME
        self.compaction = Compaction(self)
        self.releasing = bool(POUR)  # a pour's release: samples and removals, no decision until its end

    def end_release(self):
        """The pour's last batch has run (a whole number of check windows): the stop rule starts counting."""
        self.releasing = False
        self.total, self.count, self.checks = 0.0, 0, 0

    def rearm(self, t):
        """After the compaction: the stop rule starts again, armed after COMPACTION["arming"]."""
        self.total, self.count, self.checks, self.armed = 0.0, 0, 0, False
        self.arming_time = t + COMPACTION["arming"]
        if STOP_RULE == "displacement":
            self.reference = grain_positions()

    def sample(self):
        try:
            self._sample()
        except Exception as exc:
            self.failure = exc if isinstance(exc, RunFailure) else RunFailure(
                "%s: %s\n%s" % (type(exc).__name__, exc, traceback.format_exc()))
            O.pause()

    def _largest_displacement(self):
        now = grain_positions()
        largest = 0.0
        for a, b in zip(self.reference, now):
            if a is not None and b is not None:
                largest = max(largest, (b - a).norm())
        self.reference = now
        return largest

    def _sample(self):
        e = translational_kinetic_energy()
        t, step = O.time + O.dt, O.iter + 1  # at the end of this step
        # Bound and NaN at every sample, not only at checks: after a blow-up YADE's periodic collider can
        # spin for hours on grains flung across many periods before the next check comes.
        if not math.isfinite(e) or e > KINETIC_BOUND:
            _history.append((t, e))
            if not math.isfinite(e):
                raise RunFailure("kinetic energy is %r at t = %.6g s (step %d)" % (e, t, step), "non_finite")
            raise RunFailure("blow-up: kinetic energy %.6g J above the bound %.6g J (twice the energy the packing "
                             "holds) at t = %.6g s (step %d)" % (e, KINETIC_BOUND, t, step), "blow_up")
        if self.compaction.active:
            if (self.compaction.samples + 1) % (STEPS_PER_CHECK // AVERAGE_EVERY) == 0:
                _history.append((t, e))
            self.compaction.step(t, e)
            return
        self.total += e
        self.count += 1
        if self.count < self.samples:
            return
        mean = self.total / self.samples
        self.total, self.count = 0.0, 0
        _history.append((t, e))
        if self.releasing:
            removed = remove_escaped()
            if removed:
                log("t = %.6g s: %d grain(s) left the open floor's region and were removed (%d in all)" % (
                    t, removed, len(_removed)))
            return
        self.checks += 1
        if not math.isfinite(mean):
            raise RunFailure("mean kinetic energy is %r at t = %.6g s (step %d)" % (mean, t, step), "non_finite")
        removed = remove_escaped()
        if removed:
            log("t = %.6g s: %d grain(s) left the open floor's region and were removed (%d in all)" % (
                t, removed, len(_removed)))
        # len(O.bodies) keeps counting erased slots: count the bodies themselves once grains were removed.
        present = len(O.bodies) if not _removed else sum(1 for b in O.bodies if b is not None)
        if present != self.bodies - len(_removed):
            raise RunFailure("bodies were lost: %d left of %d (%d removed)" % (present, self.bodies, len(_removed)),
                             "lost_grains")
        if mean >= KINETIC_THRESHOLD:
            self.armed = True
        ready = self.armed or t >= self.arming_time if STOP_RULE == "kinetic-energy" else t >= self.arming_time
        if STOP_RULE == "kinetic-energy":
            self.value = e
            met = mean < KINETIC_THRESHOLD and e < KINETIC_THRESHOLD
        elif STOP_RULE == "unbalanced-force":
            self.value = unbalanced_force()
            met = self.value < UNBALANCED_THRESHOLD
        else:
            self.value = self._largest_displacement()
            met = self.value < DISPLACEMENT_THRESHOLD
        if ready and met:
            self.reason = STOP_RULE
        elif self.checks >= MAX_CHECKS:
            self.reason = "max-time"
        if self.reason is not None:
            O.pause()  # YADE stops once this step is complete
            return
        if time.time() >= self.next_report:
            self.next_report = time.time() + 10.0
            log("t = %.6g s, step %d, kinetic energy %.6g J (%.3g x threshold), %s %.6g" % (
                t, step, e, e / KINETIC_THRESHOLD, STOP_RULE, self.value))


_rule = None
_final_unbalanced = None


def hold_lattice():
    """A pour starts with every grain held where yade_packing.csv put it (on the lattice): all its degrees of
    freedom blocked, so it is not integrated and acts as a fixed obstacle until its batch is released."""
    for _, bid in _grains:
        O.bodies[bid].state.blockedDOFs = "xyzXYZ"
        O.bodies[bid].state.vel = Vector3(0.0, 0.0, 0.0)
        O.bodies[bid].state.angVel = Vector3(0.0, 0.0, 0.0)


def release(rule):
    """The pour's release (POUR; the LIGGGHTS script's, batch for batch): batch k, the grains of packing ids
    first..last, is moved down until its lowest centre is drop_gap + 2 r_max above the highest released centre
    (the first batch: drop_gap + r_max above the floor), freed and run for its steps. A batch that would move up
    (the pile reached the held lattice) is a failure."""
    gap, r_max = POUR["drop_gap"], POUR["r_max"]
    free = "yXZ" if DIMENSION == 2 else ""
    batches = POUR["batches"]
    for k, (first, last, steps) in enumerate(batches):
        batch = [O.bodies[bid] for gid, bid in _grains[first - 1:last] if O.bodies[bid] is not None]
        released = [O.bodies[bid] for gid, bid in _grains[:first - 1] if O.bodies[bid] is not None]
        lo = min(b.state.pos[2] for b in batch)
        if k == 0 or not released:
            dz = r_max + gap - lo
        else:
            dz = max(b.state.pos[2] for b in released) + 2.0 * r_max + gap - lo
            if dz > 0.0:
                raise RunFailure("the pile reached the held lattice: batch %d would move up by %.6g m" % (k + 1, dz))
        for b in batch:
            b.state.pos = b.state.pos + Vector3(0.0, 0.0, dz)
            b.state.blockedDOFs = free
        _collider.doSort = True  # the moved batch's bounds are found anew
        log("BTR-BATCH %d %d: grains %d..%d moved by %.6g m, %d steps" % (k + 1, len(batches), first, last, dz, steps))
        O.run(steps, True)
        if rule.failure is not None:
            raise rule.failure
    rule.end_release()


def rotate(rotation):
    """A rotating drum (ROTATION; the LIGGGHTS script's runs, snapshot for snapshot): the drum's facets turn about
    its axis (along y through x = 0, z = axis_z) at omega rad/s, lowest line towards +x (a rotation about -y),
    set by a RotationEngine before NewtonIntegrator; after each snapshot's step count the grains' positions go to
    yade_rot_K.csv. The kinetic energy is sampled there and bounded as in a relaxation. Returns "max-time"."""
    global _loop_seconds
    from yade import RotationEngine
    newton = next(i for i, e in enumerate(O.engines) if isinstance(e, NewtonIntegrator))
    O.engines = O.engines[:newton] + [RotationEngine(ids=list(_walls), rotationAxis=(0.0, -1.0, 0.0),
                                                     angularVelocity=rotation["omega"], rotateAroundZero=True,
                                                     zeroPoint=(0.0, 0.0, rotation["axis_z"]), label="drum")] + \
        O.engines[newton:]
    log("drum rotation: %.6g rad/s about y = axis through (0, 0, %.6g), %d facets, snapshots at steps %s" % (
        rotation["omega"], rotation["axis_z"], len(_walls), rotation["snapshot_steps"]))
    t0 = time.time()
    done = 0
    for k, steps in enumerate(rotation["snapshot_steps"]):
        O.run(steps - done, True)
        done = steps
        e = translational_kinetic_energy()
        _history.append((O.time, e))
        if not math.isfinite(e):
            raise RunFailure("non-finite kinetic energy at t = %.6g s" % O.time, "non_finite")
        if e > KINETIC_BOUND:
            raise RunFailure("kinetic energy %.6g J above the bound %.6g J at t = %.6g s" % (e, KINETIC_BOUND, O.time),
                             "blow_up")
        lines = ["id,x,y,z"]
        for gid, bid in _grains:
            p = O.bodies[bid].state.pos
            lines.append("%d,%.17g,%.17g,%.17g" % (gid, p[0], p[1], p[2]))
        write_atomically("yade_rot_%d.csv" % (k + 1), "\n".join(lines) + "\n")
        log("BTR-SNAPSHOT %d t = %.6g s, %d steps, process time %.3f s" % (k + 1, O.time, O.iter, time.process_time()))
    _loop_seconds = time.time() - t0
    return "max-time"


def grain_kinetic_energy():
    """Translational kinetic energy of the grains alone. O.energy["kinTrans"] also counts every body the engines
    move, and the moving floor (in a periodic cell a box far wider than the cell, of a large mass) would swamp it."""
    total = 0.0
    for _, b in present_grains():
        total += 0.5 * b.state.mass * b.state.vel.squaredNorm()
    return total


class TapWatch:
    """Inside YADE's loop while tapping (PyRunners; never raises, it records the failure and pauses YADE):
    sample() bounds the grains' kinetic energy every AVERAGE_EVERY steps (NaN or above KINETIC_BOUND is a failure);
    follow() runs at every step of a tap, after NewtonIntegrator, and keeps the floor's highest and lowest
    displacement from its rest height and its largest speed: the motion the script reports, measured on the floor
    body itself."""

    def __init__(self, floor, rest_z):
        self.floor, self.rest_z = floor, rest_z
        self.failure = None
        self.reset()

    def reset(self):
        self.highest, self.lowest, self.speed, self.steps = -float("inf"), float("inf"), 0.0, 0

    def sample(self):
        try:
            e = grain_kinetic_energy()
            t, step = O.time + O.dt, O.iter + 1
            if not math.isfinite(e) or e > KINETIC_BOUND:
                _history.append((t, e))
                if not math.isfinite(e):
                    raise RunFailure("kinetic energy is %r at t = %.6g s (step %d)" % (e, t, step), "non_finite")
                raise RunFailure("blow-up: kinetic energy %.6g J above the bound %.6g J at t = %.6g s (step %d)" % (
                    e, KINETIC_BOUND, t, step), "blow_up")
        except Exception as exc:
            self.failure = exc if isinstance(exc, RunFailure) else RunFailure("%s: %s" % (type(exc).__name__, exc))
            O.pause()

    def follow(self):
        s = O.bodies[self.floor].state
        dz = s.pos[2] - self.rest_z
        self.highest, self.lowest = max(self.highest, dz), min(self.lowest, dz)
        self.speed = max(self.speed, s.vel.norm())
        self.steps += 1


def tap(spec):
    """DEM tapping (TAP; the LIGGGHTS script's loop, tap for tap): per tap the floor body moves by
    z(t) = amplitude sin(2 pi frequency (t - t0)) for one period (steps_per_tap steps), then stands still while the
    bed rests: one check window, then up to max_rest_checks windows until the grains' kinetic energy is below
    KINETIC_THRESHOLD at the ends of two windows in a row. After each rest the grains' positions go to
    yade_tap_K.csv and the tap's record to yade_taps.json. Returns "taps".
    The floor is moved by YADE's HarmonicMotionEngine, which sets the floor's velocity at each step before
    NewtonIntegrator moves it by velocity x dt: v = -A omega sin(omega t + fi), t YADE's absolute time. With
    A = amplitude sin(theta / 2) / (theta / 2) and fi = theta / 2 - pi / 2 - omega t0 (theta = omega dt), the
    velocity of step n is exactly (z(t_n+1) - z(t_n)) / dt, so the floor is at z(t_n) after every step n and back at
    its rest height after the period (to round-off, which is then removed): it starts from rest at z = 0 with the
    speed of the sine's first step, as LIGGGHTS' wiggle. Between taps the engine is dead and the floor's velocity
    zero."""
    global _loop_seconds
    import __main__
    from yade.wrapper import HarmonicMotionEngine
    if _floor is None:
        raise RunFailure("tapping: the scene has no floor to move")
    floor = O.bodies[_floor]
    rest = Vector3(floor.state.pos)
    amplitude, frequency = spec["amplitude"], spec["frequency"]
    omega = 2.0 * math.pi * frequency
    theta = omega * O.dt
    motion = HarmonicMotionEngine(ids=[_floor], A=Vector3(0.0, 0.0, amplitude * math.sin(0.5 * theta) / (0.5 * theta)),
                                  f=Vector3(0.0, 0.0, frequency), fi=Vector3(0.0, 0.0, 0.0), dead=True, label="tap_floor")
    watch = TapWatch(_floor, rest[2])
    __main__._btr_tap_watch = watch
    follow = PyRunner(command="_btr_tap_watch.follow()", iterPeriod=1, nDone=1, dead=True, label="tap_follow")
    newton = next(i for i, e in enumerate(O.engines) if isinstance(e, NewtonIntegrator))
    O.engines = O.engines[:newton] + [motion] + O.engines[newton:] + [
        PyRunner(command="_btr_tap_watch.sample()", iterPeriod=AVERAGE_EVERY, iterLast=O.iter - 1, nDone=1,
                 label="tap_guard"), follow]
    log("tapping: %d taps of the floor (body %d), amplitude %.6g m at %.6g Hz, %d steps per tap; rest windows of %d "
        "steps, at most %d after the first" % (spec["taps"], _floor, amplitude, frequency, spec["steps_per_tap"],
                                               spec["steps_per_check"], spec["max_rest_checks"]))

    def run(steps):
        O.run(steps, True)
        if watch.failure is not None:
            raise watch.failure
        e = grain_kinetic_energy()
        _history.append((O.time, e))
        if not math.isfinite(e):
            raise RunFailure("kinetic energy is %r at t = %.6g s" % (e, O.time), "non_finite")
        if e > KINETIC_BOUND:
            raise RunFailure("blow-up: kinetic energy %.6g J above the bound %.6g J at t = %.6g s" % (
                e, KINETIC_BOUND, O.time), "blow_up")
        return e

    records = []
    t_loop = time.time()
    for k in range(1, spec["taps"] + 1):
        t0 = O.time
        motion.fi = Vector3(0.0, 0.0, 0.5 * theta - 0.5 * math.pi - omega * t0)
        watch.reset()
        follow.iterLast = O.iter - 1  # follow from this step on (a PeriodicEngine runs once iter - iterLast >= 1)
        motion.dead = follow.dead = False
        moved_kinetic = run(spec["steps_per_tap"])
        motion.dead = follow.dead = True
        floor.state.vel = Vector3(0.0, 0.0, 0.0)
        floor.state.angVel = Vector3(0.0, 0.0, 0.0)
        end = floor.state.pos[2] - rest[2]
        if watch.steps != spec["steps_per_tap"] or not abs(end) <= 1e-9 * amplitude:
            raise RunFailure("tap %d: the floor ended %.6g m from its rest height after %d steps of %d" % (
                k, end, watch.steps, spec["steps_per_tap"]), "engine_error")
        floor.state.pos = rest
        moved_time = O.time
        previous = run(spec["steps_per_check"])
        e, settled = previous, False
        for _ in range(spec["max_rest_checks"]):
            e = run(spec["steps_per_check"])
            if previous < KINETIC_THRESHOLD and e < KINETIC_THRESHOLD:
                settled = True
                break
            previous = e
        lines = ["id,x,y,z"]
        for gid, bid in _grains:
            p = O.bodies[bid].state.pos
            lines.append("%d,%.17g,%.17g,%.17g" % (gid, p[0], p[1], p[2]))
        write_atomically("yade_tap_%d.csv" % k, "\n".join(lines) + "\n")
        records.append({"tap": k, "moved_time": moved_time, "moved_kinetic": moved_kinetic, "rested_time": O.time,
                        "rested_kinetic": e, "settled": settled, "step": O.iter,
                        "floor_highest": watch.highest, "floor_lowest": watch.lowest,
                        "floor_peak_speed": watch.speed, "floor_end": end, "process_seconds": time.process_time()})
        write_atomically(TAPS_FILE, json.dumps(records, indent=1) + "\n")
        log("BTR-TAP %d %s: floor %.6g..%.6g m (peak speed %.6g m/s, %.3g m off at the end), kinetic %.6g J when it "
            "stopped, %.6g J at t = %.6g s, step %d" % (k, "settled" if settled else "max-rest", watch.lowest,
                                                        watch.highest, watch.speed, end, moved_kinetic, e, O.time,
                                                        O.iter))
    _loop_seconds = time.time() - t_loop
    return "taps"


def relax():
    """Runs the relaxation in one O.run() call (the StopRule's PyRunner pauses it) and returns the stop
    reason; the wall time of the loop alone is in _loop_seconds."""
    global _rule, _loop_seconds
    build_engines()
    O.dt = COMPACTION["timestep"] if COMPACTION else TIMESTEP
    log("YADE %s, %d threads, model %s, %d grains (%d clumps), %d wall bodies" % (
        getattr(yade.config, "version", "?"), O.numThreads, MODEL, len(_grains), len(_clumps), len(_walls)))
    log("time step %.6g s: %s (YADE's P-wave estimate: %.6g s)" % (TIMESTEP, TIMESTEP_RULE, utils.PWaveTimeStep()))
    log("stop rule %s (kinetic %.6g J, unbalanced force %.6g, displacement %.6g m) every %d steps, from t >= %.6g s; "
        "at most %d checks; blow-up above %.6g J; damping %.6g" % (
            STOP_RULE, KINETIC_THRESHOLD, UNBALANCED_THRESHOLD, DISPLACEMENT_THRESHOLD, STEPS_PER_CHECK, ARMING_TIME,
            MAX_CHECKS, KINETIC_BOUND, DAMPING))
    if REGION is not None:
        log("open floor: grains leaving x in [%.6g, %.6g], y in [%.6g, %.6g] m are removed" % REGION)
    if POUR:
        hold_lattice()
        log("pour: %d batches from the lattice, drop gap %.6g m; the stop rule runs after the last" % (
            len(POUR["batches"]), POUR["drop_gap"]))
    _history.append((0.0, sum(0.5 * O.bodies[b].state.mass * O.bodies[b].state.vel.squaredNorm() for _, b in _grains)))
    if globals().get("ROTATION"):
        return rotate(ROTATION)
    if globals().get("TAP"):
        return tap(TAP)
    _rule = StopRule()
    # PyRunner commands run in __main__, which is not this script's namespace under the `yade` launcher.
    import __main__
    __main__._btr_stop_rule = _rule
    # First run after AVERAGE_EVERY steps (at O.iter = AVERAGE_EVERY - 1), then every AVERAGE_EVERY steps;
    # nDone = 1 skips PeriodicEngine's bookkeeping first call, which would reset iterLast to 0.
    O.engines = O.engines + [PyRunner(command="_btr_stop_rule.sample()", iterPeriod=AVERAGE_EVERY,
                                      iterLast=O.iter - 1, nDone=1, label="stop_rule")]
    t0 = time.time()
    if POUR:
        release(_rule)
    _rule.compaction.start()
    steps = MAX_CHECKS * STEPS_PER_CHECK
    if COMPACTION:  # each friction scale (slab) of the compaction may run up to max_time before the settle's
        stages = len(COMPACTION.get("slabs") or COMPACTION["friction_scales"])
        steps += stages * COMPACTION["max_samples_per_scale"] * AVERAGE_EVERY
    O.run(steps, True)  # returns when the rule pauses YADE (or at the last step)
    _loop_seconds = time.time() - t0
    if _rule.failure is not None:
        raise _rule.failure
    if _rule.reason is None:
        raise RunFailure("the run ended after %d steps without a stop-rule decision" % O.iter)
    return _rule.reason


def main():
    global _final_unbalanced
    t0 = time.time()
    try:
        scene()
        reason = relax()
        remove_escaped()
        _final_unbalanced = unbalanced_force()
        if not math.isfinite(_final_unbalanced):
            _final_unbalanced = None
        for gid, bid in _grains:
            if O.bodies[bid] is None:
                continue
            if O.bodies[bid].state.pos[2] < 0.0:
                raise RunFailure("grain %d fell through the floor (z = %.6g m)" % (gid, O.bodies[bid].state.pos[2]),
                                 "outside_container")
        write_outputs()
        wall = time.time() - t0
        log("unbalanced force at the end: %s; %d grain(s) removed" % (_final_unbalanced, len(_removed)))
        log("stopped by %s at t = %.6g s after %d steps, %.3g s wall time, %.3g s of them stepping (%.4g steps/s)" % (
            reason, O.time, O.iter, wall, _loop_seconds, O.iter / _loop_seconds if _loop_seconds > 0 else 0.0))
        write_status("ok", reason, "", wall)
        return 0
    except Exception as exc:
        message = str(exc) if isinstance(exc, RunFailure) else "%s: %s" % (type(exc).__name__, exc)
        log(traceback.format_exc())
        log("FAILED: " + message)  # last, so that the tail of the log names the failure
        if _history:
            write_history()
        write_status("failed", "", message, time.time() - t0, exc.kind if isinstance(exc, RunFailure) else "engine_error")
        return 1
