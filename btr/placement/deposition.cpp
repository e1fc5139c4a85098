// The placement of one grain is a sequence of events (docs/design.md section 3). Its state is the centre
// x and the active contacts; each step asks where gravity pushes it (descend), and moves it along
// the path those contacts allow (a vertical fall, a circular arc, or the curve along a cylinder
// wall) up to the first event: a new contact, a support lifting off, or the lowest point.
#include "btr/placement/deposition.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <new>
#include <type_traits>
#include <sstream>

#include "btr/placement/circle_arc.h"
#include "btr/placement/cluster_placement.h"
#include "btr/placement/contacts.h"
#include "btr/placement/descent.h"
#include "btr/placement/grain_arc_event.h"
#include "btr/placement/mesh_index.h"
#include "btr/placement/mesh_placement.h"
#include "btr/placement/neighbour_grid.h"
#include "btr/placement/obstacle.h"
#include "btr/placement/path_graze.h"
#include "btr/placement/walls.h"

namespace btr {
namespace {

// Events in a row without the grain moving, its contacts cycling, after which it is wedged (place()).
constexpr int kWedgedEvents = 12;

// A wall path's steps look for grains entered and left between their samples deeper than kGrazeDepth radii
// (shallower is a tangency: the self-check's overlap tolerance); the first step leaves out the grains the walk
// starts within kTouching radii of (the path leaves them). first_graze, btr/placement/path_graze.h.
constexpr double kGrazeDepth = 1e-9, kTouching = 1e-9;

// splitmix64: a deterministic hash for tie-breaks (which way a grain balanced on a top rolls).
std::uint64_t mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// A grain rolling on one support keeps its centre on the support's contact sphere |x - p.c| = p.R, so
// of the grains gathered around its path only those whose own contact sphere reaches that one can ever
// touch it (the margin is far above round-off; the others could only fail the exact test).
bool can_meet_on(const Obstacle& p, const Vec3& c, double R) {
  const double reach = (p.R + R) * (1.0 + 1e-9);
  return (c - p.c).squaredNorm() < reach * reach;
}

// Does a grain at x overlap sphere o by more than tol, o.gap(x) < -tol? The squared distance first
// spares the root for the grains clearly apart (tol is far above its round-off).
bool overlaps(const Obstacle& o, const Vec3& x, double tol) {
  return (x - o.c).squaredNorm() < o.R * o.R && o.gap(x) < -tol;
}

}  // namespace

struct Deposition::Impl {
  int dimension;
  Container container;
  double r_max;
  int max_events;
  Grains grains;
  NeighbourGrid grid;
  double top = 0.0;  // highest grain top so far
  std::int32_t clusters = 0;  // rigid clusters placed so far
  std::vector<Obstacle> walls;  // the container as obstacles for the grain being placed (reused)
  std::unique_ptr<MeshIndex> mesh;  // a mesh container's triangles (btr/placement/mesh_placement.cpp)

  Impl(int dim, const Container& c, double rmax, int events)
      : dimension(dim), container(c), r_max(rmax), max_events(events), grid(dim, c, rmax) {
    if (c.kind == ContainerKind::Mesh) mesh = std::make_unique<MeshIndex>(*c.mesh, 2.0 * rmax);
  }
  const Grain& place_mesh(std::int64_t id, const Drop& drop, double px, double py);

  static Obstacle sphere(std::int32_t i, const Vec3& centre, double radius, int image, double r) {
    Obstacle o;
    o.kind = Obstacle::Kind::Sphere;
    o.key = sphere_key(i, image);
    o.c = centre;
    o.R = r + radius;
    return o;
  }

  const Grain& place(const Drop& drop);
  void fall(Vec3& x, double r, Contacts& active, const std::vector<Obstacle>& walls);
  void roll_on_arc(Vec3& x, double r, Contacts& active, const CircleArc& arc, const std::vector<Obstacle>& walls);
  // The curve a grain follows on one grain while pressed against the cylinder or the drum (walk_wall_path).
  struct WallPath {
    double start = 0.0, step = 0.0;   // the angle the walk starts at, and its step (signed, 0.05 r of arc)
    double radius = 0.0;              // of the wall's centre surface
    bool start_off_curve = false;     // the start may lie off the curve (the drum): x stands for it
    std::vector<Obstacle> walls;      // the flat walls the path can meet
  };
  template <class At, class Ends, class Tangent, class Spread, class Near>
  bool walk_wall_path(Vec3& x, double r, Contacts& active, int sphere, int wall, const WallPath& path, At at, Ends ends,
                      Tangent tangent, Spread spread, Near near);
  bool roll_along_drum(Vec3& x, double r, Contacts& active, int sphere, int drum, const Vec3& d,
                       const std::vector<Obstacle>& walls);
  bool drum_rest(const Vec3& x, const Contacts& active) const;
  void drum_start(Vec3& x, double z, double r) const;
  bool roll_along_cylinder(Vec3& x, double r, Contacts& active, int sphere, int cylinder, const Vec3& d,
                           const std::vector<Obstacle>& walls);
  bool at_bottom(const Vec3& x, const Contacts& active) const;
  double free_start(double x, double y, double z, double r) const;
  Vec3 tie_break(const Vec3& x, const Contacts& active, std::uint64_t salt) const;
  void back_inside_walls(std::int64_t id, Vec3& x, double r) const;
  static PlacementError too_many_contacts(std::int64_t id, const Vec3& x) {
    std::ostringstream why;
    why << "more than " << kMaxContacts << " simultaneous contacts at (" << x.x() << ", " << x.y() << ", " << x.z()
        << "): the engine holds at most " << kMaxContacts;
    return PlacementError(id, why.str());
  }
};

// A grain rolling along a wall on grains that touch it creeps into it by round-off (~1e-10 r per
// event, and the next grain rolling on it goes further): put it back on the wall, flat, cylinder or
// drum. Farther than 1e-7 r beyond a wall it is no round-off: an error naming the grain.
void Deposition::Impl::back_inside_walls(std::int64_t id, Vec3& x, double r) const {
  const char* names[] = {"grain", "flat wall", "cylinder wall", "drum wall"};
  for (const Obstacle& w : walls) {
    const double g = w.gap(x);
    if (!(g < 0.0)) continue;
    if (g <= -1e-7 * r) {
      std::ostringstream why;
      why << "ends " << -g / r << " radii beyond the " << names[static_cast<int>(w.kind)] << " at (" << x.x() << ", "
          << x.y() << ", " << x.z() << ")";
      throw PlacementError(id, why.str());
    }
    switch (w.kind) {
      case Obstacle::Kind::Plane: x -= g * w.c; break;
      case Obstacle::Kind::Cylinder: {
        // Onto the surface, then inwards by whole ulps until the gap is not negative.
        const double s = w.R / std::hypot(x.x(), x.y());
        x.x() *= s, x.y() *= s;
        for (int k = 0; k < 4 && w.gap(x) < 0.0; ++k) x.x() *= 1.0 - 0x1p-52, x.y() *= 1.0 - 0x1p-52;
        break;
      }
      case Obstacle::Kind::Drum: {
        const double dz = x.z() - w.c.z(), s = w.R / std::sqrt(x.x() * x.x() + dz * dz);
        x.x() *= s, x.z() = w.c.z() + dz * s;
        for (int k = 0; k < 4 && w.gap(x) < 0.0; ++k) x.x() *= 1.0 - 0x1p-52, x.z() = w.c.z() + (x.z() - w.c.z()) * (1.0 - 0x1p-52);
        break;
      }
      case Obstacle::Kind::Sphere: break;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Fall: straight down to the highest contact below (docs/design.md section 3: z_j + sqrt((r + r_j)^2 - h^2)).
void Deposition::Impl::fall(Vec3& x, double r, Contacts& active, const std::vector<Obstacle>& walls) {
  const double tol = 1e-12 * r;
  Event ev(x.z() - r);  // floor at z = r: t measures the drop
  ev.hits.add(walls[0]);
  const double reach = r + r_max;
  grid.visit_column_down(
      x.x(), x.y(), reach, x.z() + reach,
      [&](double layer_top) { return layer_top + reach > x.z() - ev.t; },
      [&](std::int32_t i, const Vec3& centre, double radius, int image) {
        const double R = r + radius;
        const double dx = x.x() - centre.x(), dy = x.y() - centre.y();
        const double s = R * R - dx * dx - dy * dy;
        if (s <= 1e-12 * R * R) return;  // passes beside it (or grazes its equator)
        const double z_hit = centre.z() + std::sqrt(s);
        if (z_hit > x.z() + tol) return;
        const Obstacle o = sphere(i, centre, radius, image, r);
        if (active.has(o.key)) return;
        ev.offer(x.z() - z_hit, o, tol);
      });
  if (container.kind == ContainerKind::Drum) {
    // The drum's lower wall below x: z = z_axis - sqrt(R^2 - x^2).
    const Obstacle& w = walls.back();
    const double s = w.R * w.R - x.x() * x.x();
    if (s >= 0.0 && !active.has(w.key)) {  // s = 0: a start on the drum's side, level with the axis
      const double z_hit = w.c.z() - std::sqrt(s);
      if (z_hit <= x.z() + tol) ev.offer(x.z() - z_hit, w, tol);
    }
  }
  x.z() -= ev.t;
  active.add_all(ev.hits);
}

// ---------------------------------------------------------------------------------------------
// Roll along a circular arc (one support: a meridian; two: where their surfaces meet).
void Deposition::Impl::roll_on_arc(Vec3& x, double r, Contacts& active, const CircleArc& arc,
                                   const std::vector<Obstacle>& walls) {
  const double t_tol = 1e-13;
  Event ev(arc);

  auto offer_plane = [&](const Obstacle& o) {
    if (active.has(o.key)) return;
    const double g0 = o.c.dot(arc.C) - o.R;
    const double a = arc.rho * o.c.dot(arc.u), b = arc.rho * o.c.dot(arc.v);
    // Touching includes a start a hair inside (round-off of earlier rolls along the wall, up to the 1e-7 r
    // that back_inside_walls puts right): moving further in from there is a contact at once.
    const bool touching = g0 + a <= 1e-9 * r;
    if (touching && b < -kApproach * arc.rho) { ev.offer(0.0, o, t_tol, kArcStart); return; }
    ArcDirection direction;
    const double t = first_rising_root(-a, -b, g0, touching ? kSkipTangency : 0.0, ev.reach(t_tol), 5.0, &direction);
    if (t >= 0.0) ev.offer(t, o, t_tol, direction);
  };
  // The vertical cylinder and a drum (an arc out of the planes y = const): the squared distance from the
  // axis is of degree 2 in cos t, sin t; its first rise through R^2 by branch and bound.
  auto offer_tube = [&](const Obstacle& o, int axis) {
    if (active.has(o.key)) return;
    ev.resolve();  // the exit's search is bounded by the event
    const double t = first_tube_exit(arc, o.kind == Obstacle::Kind::Drum ? o.c : Vec3::Zero(), axis, o.R, ev.t + t_tol);
    if (t >= 0.0) ev.offer(t, o, t_tol);
  };
  auto offer_drum = [&](const Obstacle& o) {
    if (active.has(o.key)) return;
    // The arc lies inside the drum's centre surface (its circle does: the distance of any point of it
    // from the axis is at most that of C plus rho; or the whole arc's box does): no contact possible.
    // The circle first, as it needs no trigonometry.
    const double cz = arc.C.z() - o.c.z();
    if (std::sqrt(arc.C.x() * arc.C.x() + cz * cz) + arc.rho < o.R * (1.0 - 1e-9)) return;
    Vec3 lo, hi;
    arc.bounds(lo, hi);
    const double fx = std::max(std::abs(lo.x()), std::abs(hi.x()));
    const double fz = std::max(std::abs(lo.z() - o.c.z()), std::abs(hi.z() - o.c.z()));
    if (fx * fx + fz * fz < o.R * o.R * (1.0 - 1e-9)) return;
    if (std::abs(arc.u.y()) > 1e-12 || std::abs(arc.v.y()) > 1e-12) {
      offer_tube(o, 1);
      return;
    }
    // An arc in a plane y = const: squared distance from the axis D(t) = K + a cos t + b sin t; the
    // grain enters the wall where D rises through R^2.
    Vec3 w = arc.C - o.c;
    w.y() = 0.0;
    const double K = w.squaredNorm() + arc.rho * arc.rho;
    const double a = 2.0 * arc.rho * w.dot(arc.u), b = 2.0 * arc.rho * w.dot(arc.v);
    const double R2 = o.R * o.R;
    const bool touching = K + a - R2 >= -1e-9 * R2;  // a start a hair beyond the wall included, as for planes
    if (touching && b > 2.0 * kApproach * arc.rho * o.R) { ev.offer(0.0, o, t_tol, kArcStart); return; }
    ArcDirection direction;
    const double t = first_rising_root(a, b, R2 - K, touching ? kSkipTangency : 0.0, ev.reach(t_tol), 5.0, &direction);
    if (t >= 0.0) ev.offer(t, o, t_tol, direction);
  };
  // In a drum the floor only touches the drum's lowest line, where the drum wall is met first.
  const bool drum_container = container.kind == ContainerKind::Drum;
  for (const Obstacle& w : walls) {
    if (w.kind == Obstacle::Kind::Cylinder) offer_tube(w, 2);
    else if (w.kind == Obstacle::Kind::Drum) offer_drum(w);
    else if (drum_container && w.is_floor()) continue;
    else offer_plane(w);
  }
  offer_grains_on_arc(grid, r, r_max, active, arc, x, ev);
  if (active.n == 2) offer_lift_offs(active, arc, ev);

  x = arc.at(ev.t, ev.direction);
  if (ev.lift_off >= 0) active.remove(ev.lift_off);
  active.add_all(ev.hits);
}

// ---------------------------------------------------------------------------------------------
// A grain rolling on one grain p while pressed against a curved wall (the cylinder, or the drum) keeps its
// centre on the curve where p's contact sphere meets the wall's centre surface: not a circle. The walk follows it
// by its angle f about the wall's axis in steps of 0.05 r of arc, proves each step clear between its ends or
// finds a grain entered in it (first_graze), and locates the first event by bisection. The path supplies at(f)
// (the centre, and whether f is on the curve), ends(f, on) (an end of the curve at f: 2 lift off p, 4 its lowest
// point; else 0), tangent(f, P, T) (the unit tangent T along the motion at P, or 4 where the motion turns up, past
// the lowest point), spread(f, h) (a bound of the centre's travel from f over h) and near(c, R, here, travel) (can a grain centred
// at c, R = r + its radius, be met within `travel` of here?). Returns true at the lowest point of the curve.
template <class At, class Ends, class Tangent, class Spread, class Near>
bool Deposition::Impl::walk_wall_path(Vec3& x, double r, Contacts& active, int si, int wi, const WallPath& path,
                                      At at, Ends ends, Tangent tangent, Spread spread, Near near) {
  const Obstacle p = active.item[si];
  const Obstacle wall = active.item[wi];
  const Vec3 z = Vec3::UnitZ();
  const double gap_tol = 1e-12 * r;
  // 0: continue; 1: new contact; 2: lift off p; 3: lift off the wall; 4: lowest point passed.
  std::vector<Obstacle> candidates;
  // The step's test at angle f, the centre there being P (on: f is on the curve).
  auto condition_at = [&](double f, const Vec3& P, bool ok) -> int {
    if (const int end = ends(f, ok)) return end;
    for (const Obstacle& o : candidates)
      if (overlaps(o, P, gap_tol) && !active.has(o.key)) return 1;
    for (const Obstacle& w : path.walls)
      if (w.gap(P) < -gap_tol) return 1;
    Vec3 T;
    if (const int turn = tangent(f, P, T)) return turn;
    const Vec3 g_perp = z - z.dot(T) * T;
    const Vec3 np = p.normal(P), nw = wall.normal(P);
    if (unloads(g_perp, np, nw)) return 2;
    if (unloads(g_perp, nw, np)) return 3;
    return 0;
  };
  auto condition = [&](double f) {
    const auto [P, ok] = at(f);
    return condition_at(f, P, ok);
  };
  // What a step could pass between its samples (the candidates not in contact, and the walls).
  std::vector<Obstacle> partners;
  auto point = [&](double f) {
    const auto [P, ok] = at(f);
    return ok ? P : Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  };
  const double step = path.step;
  const double reach = 2.0 * r + 2.0 * r_max;
  double f = path.start;
  // The centre at f, where the step from f starts: where the start lies off the curve, x stands for it.
  Vec3 Pf = path.start_off_curve ? x : point(f);
  for (int chunk = 0; chunk < 1000; ++chunk) {
    candidates.clear();
    // Where the start lies off the curve (the drum's branches meeting), the first stretch from x itself.
    const Vec3 here = chunk == 0 && path.start_off_curve ? x : at(f).first;
    const double travel = 20 * std::abs(step) * path.radius;
    const Vec3 span = Vec3::Constant(reach + travel);
    grid.visit_box(here - span, here + span, [&](std::int32_t i, const Vec3& c, double radius, int image) {
      if (near(c, r + radius, here, travel) && can_meet_on(p, c, r + radius))
        candidates.push_back(sphere(i, c, radius, image, r));
    });
    partners.clear();
    for (const Obstacle& o : candidates)
      if (!active.has(o.key)) partners.push_back(o);
    for (const Obstacle& w : path.walls) partners.push_back(w);
    for (int k = 0; k < 20; ++k) {
      double f1 = f + step;
      const auto [P1, on1] = at(f1);
      if (condition_at(f1, P1, on1) == 0) {  // then f1 is on the curve (ends(f1, false) is an end)
        const double touching = f == path.start ? kTouching * r : -std::numeric_limits<double>::infinity();
        const double graze = first_graze(f, f1, Pf, P1, partners, kGrazeDepth * r, touching, point, spread);
        if (std::isnan(graze)) {
          f = f1;
          Pf = P1;
          continue;
        }
        f1 = graze;  // a partner entered and left between the samples: its entry lies in (f, graze]
      }
      double f0 = f;
      for (int it = 0; it < 200 && std::abs(f1 - f0) > 1e-15; ++it) {
        const double fm = 0.5 * (f0 + f1);
        (condition(fm) == 0 ? f0 : f1) = fm;
      }
      // No progress from a start off the curve: the grain stays where it is.
      if (!(path.start_off_curve && f0 == path.start)) x = at(f0).first;
      switch (condition(f1)) {
        case 1: {
          const Vec3 P1 = at(f1).first;
          for (const Obstacle& o : candidates)
            if (o.gap(P1) < -gap_tol) active.add(o);
          for (const Obstacle& w : path.walls)
            if (w.gap(P1) < -gap_tol) active.add(w);
          return false;
        }
        case 2: active.remove(si); return false;
        case 3: active.remove(wi); return false;
        case 4: return true;  // the lowest point of the curve
        default:
          f = f1;
          Pf = point(f1);
          continue;
      }
    }
  }
  x = at(f).first;
  return false;
}

// ---------------------------------------------------------------------------------------------
// Roll on one grain while pressed against the cylinder wall: the walk along its curve, |x_h| = R at distance
// R_p from the support, by the azimuth. Returns true when the grain comes to rest at the lowest point of that curve.
bool Deposition::Impl::roll_along_cylinder(Vec3& x, double r, Contacts& active, int si, int ci, const Vec3& d,
                                           const std::vector<Obstacle>& walls) {
  const Obstacle p = active.item[si];
  const Obstacle cyl = active.item[ci];
  const double Rc = cyl.R;
  WallPath path;
  path.start = std::atan2(x.y(), x.x());
  const double sign = d.dot(Vec3(-std::sin(path.start), std::cos(path.start), 0.0)) >= 0.0 ? 1.0 : -1.0;
  path.step = sign * 0.05 * r / Rc;
  path.radius = Rc;
  path.walls = {walls[0]};
  const double zside = x.z() >= p.c.z() ? 1.0 : -1.0;
  auto at = [&](double f) -> std::pair<Vec3, bool> {
    Vec3 P(Rc * std::cos(f), Rc * std::sin(f), 0.0);
    const double h2 = (P.head<2>() - p.c.head<2>()).squaredNorm();
    const double s = p.R * p.R - h2;
    if (s < 0.0) return {P, false};
    P.z() = p.c.z() + zside * std::sqrt(s);
    return {P, true};
  };
  auto ends = [](double, bool on) { return on ? 0 : 2; };
  auto tangent = [&](double f, const Vec3& P, Vec3& T) {
    // Height change along the motion: dz/dphi = zside * (ds/dphi) / (2 sqrt(s)).
    const Vec3 dPh(-Rc * std::sin(f), Rc * std::cos(f), 0.0);
    const double s = p.R * p.R - (P.head<2>() - p.c.head<2>()).squaredNorm();
    const double dz = zside * (-(P.head<2>() - p.c.head<2>()).dot(dPh.head<2>())) / std::sqrt(std::max(s, 1e-300));
    if (sign * dz > 0.0) return 4;
    T = Vec3(sign * dPh.x(), sign * dPh.y(), sign * dz).normalized();
    return 0;
  };
  auto spread = [&](double f, double h) {
    const double q = std::hypot(Rc * std::cos(f) - p.c.x(), Rc * std::sin(f) - p.c.y());
    return tube_path_spread(Rc, h, q, p.R * p.R - q * q);
  };
  auto near = [](const Vec3&, double, const Vec3&, double) { return true; };
  return walk_wall_path(x, r, active, si, ci, path, at, ends, tangent, spread, near);
}

// ---------------------------------------------------------------------------------------------
// A given start height (dynamic BTR), raised above the floor and then straight up out of every fixed
// grain it overlaps (each lift can only meet grains higher up, so this ends).
double Deposition::Impl::free_start(double x, double y, double z, double r) const {
  z = std::max(z, r);
  const double reach = r + r_max;
  for (bool moved = true; moved;) {
    moved = false;
    grid.visit_box(Vec3(x - reach, y - reach, z - reach), Vec3(x + reach, y + reach, z + reach),
                   [&](std::int32_t, const Vec3& c, double radius, int) {
                     const double R = r + radius, dx = x - c.x(), dy = y - c.y(), dz = z - c.z();
                     if (dx * dx + dy * dy + dz * dz >= R * R * (1.0 - 1e-12)) return;
                     const double up = c.z() + std::sqrt(std::max(0.0, R * R - dx * dx - dy * dy));
                     if (up > z) z = up, moved = true;
                   });
  }
  return z;
}

// ---------------------------------------------------------------------------------------------
// The drum: a start inside the drum's section at x (a lifted grain never leaves the drum), moved
// straight up out of fixed grains. Near the wall the section is short: when the fixed grains fill it
// up to the wall, the start moves inwards in steps of one radius to the first column with room.
void Deposition::Impl::drum_start(Vec3& x, double z, double r) const {
  const double Rc = container.radius - r, za = container.radius;
  // At |x| = Rc the wall is vertical and level with the axis: gravity is tangent to it and the grain
  // would alternate between meeting it and leaving it. A start there is moved 1e-12 Rc inwards.
  const double edge = Rc * (1.0 - 1e-12);
  const double x0 = std::clamp(x.x(), -edge, edge), inward = x0 > 0.0 ? -1.0 : 1.0;
  for (int k = 0; k * r <= std::abs(x0) + r; ++k) {
    const double xk = k * r >= std::abs(x0) ? 0.0 : x0 + inward * k * r;
    const double half_chord = std::sqrt(std::max(0.0, Rc * Rc - xk * xk));
    const double top_inside = za + half_chord;
    const double zk = free_start(xk, x.y(), std::clamp(z, za - half_chord, top_inside), r);
    if (zk <= top_inside + 1e-12 * r) {
      x.x() = xk;
      x.z() = std::min(zk, top_inside);
      return;
    }
  }
  std::ostringstream why;
  why << "no room in the drum for a grain dropped at x = " << x0 << ": the grains already placed fill it";
  throw ContainerFull(static_cast<std::int64_t>(grains.size()) + 1, why.str());
}

// At rest on the drum wall: alone or with an end wall (gravity balanced only on the lowest line), or
// with one grain at the lowest point of their common curve (heights either way along it are higher,
// or the curve ends there).
bool Deposition::Impl::drum_rest(const Vec3& x, const Contacts& active) const {
  int di = -1, si = -1, spheres = 0;
  for (int i = 0; i < active.n; ++i) {
    if (active.item[i].kind == Obstacle::Kind::Drum) di = i;
    if (active.item[i].kind == Obstacle::Kind::Sphere) ++spheres, si = i;
  }
  if (di < 0) return false;
  if (spheres == 0) return true;
  if (spheres > 1 || dimension == 2) return false;
  const Obstacle& w = active.item[di];
  const Obstacle& p = active.item[si];
  const double theta = std::atan2(x.x(), w.c.z() - x.z()), dtheta = 1e-4;
  for (double f : {theta - dtheta, theta + dtheta}) {
    const double px = w.R * std::sin(f), pz = w.c.z() - w.R * std::cos(f);
    const double s = p.R * p.R - (px - p.c.x()) * (px - p.c.x()) - (pz - p.c.z()) * (pz - p.c.z());
    if (s >= 0.0 && pz < x.z()) return false;
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Roll on one grain while pressed against the drum wall (3D): the walk along its curve (centre on the drum's centre
// surface at distance R_p from the support) by the angle theta about the axis (height z_axis - R cos theta).
// y comes from the support: y = y_p +- sqrt(R_p^2 - (x - x_p)^2 - (z - z_p)^2). The path goes down, towards
// theta = 0; it ends at theta = 0 or where the two branches meet (y = y_p), the lowest point of the closed curve.
// Returns true when the grain comes to rest there.
bool Deposition::Impl::roll_along_drum(Vec3& x, double r, Contacts& active, int si, int di, const Vec3& d,
                                       const std::vector<Obstacle>& walls) {
  const Obstacle p = active.item[si];
  const Obstacle drum = active.item[di];
  const double Rc = drum.R, za = drum.c.z();
  WallPath path;
  path.start = std::atan2(x.x(), za - x.z());
  const double sign = path.start > 0.0 ? -1.0 : 1.0;
  path.step = sign * 0.05 * r / Rc;
  path.radius = Rc;
  // Where the branches meet, y = y_p +- sqrt(s) turns s's round-off into up to ~1e-6 r of y: the path's start can
  // lie a hair into an end wall the grain touches, or off the path, s < 0.
  path.start_off_curve = true;
  for (const Obstacle& w : walls)
    if (w.key != drum.key && !w.is_floor()) path.walls.push_back(w);
  // The branch the grain is on; where the branches meet (y = y_p, up to round-off), the one the descent
  // takes (switching branch there moves the grain by at most 2e-8 r, along the contact with p).
  const double dy0 = x.y() - p.c.y();
  const double yside = std::abs(dy0) <= 1e-8 * r && d.y() != 0.0 ? (d.y() > 0.0 ? 1.0 : -1.0) : (dy0 >= 0.0 ? 1.0 : -1.0);
  auto at = [&](double f) -> std::pair<Vec3, bool> {
    Vec3 P(Rc * std::sin(f), 0.0, za - Rc * std::cos(f));
    const double s = p.R * p.R - (P.x() - p.c.x()) * (P.x() - p.c.x()) - (P.z() - p.c.z()) * (P.z() - p.c.z());
    if (s < 0.0) return {P, false};
    P.y() = p.c.y() + yside * std::sqrt(s);
    return {P, true};
  };
  auto ends = [&](double f, bool on) { return !on || sign * f > 0.0 ? 4 : 0; };
  auto tangent = [&](double f, const Vec3& P, Vec3& T) {
    const double s = p.R * p.R - (P.x() - p.c.x()) * (P.x() - p.c.x()) - (P.z() - p.c.z()) * (P.z() - p.c.z());
    const double dx = Rc * std::cos(f), dz = Rc * std::sin(f);
    const double dy = -yside * ((P.x() - p.c.x()) * dx + (P.z() - p.c.z()) * dz) / std::sqrt(std::max(s, 1e-300));
    T = Vec3(sign * dx, sign * dy, sign * dz).normalized();
    return 0;
  };
  auto spread = [&](double f, double h) {
    const double q = std::hypot(Rc * std::sin(f) - p.c.x(), za - Rc * std::cos(f) - p.c.z());
    return tube_path_spread(Rc, h, q, p.R * p.R - q * q);
  };
  // In x-z the centre stays on the drum's circle, within `travel` of here for a stretch's 20 steps.
  auto near = [](const Vec3& c, double R, const Vec3& here, double travel) {
    const double dx = c.x() - here.x(), dz = c.z() - here.z(), reach = (R + travel) * (1.0 + 1e-9);
    return dx * dx + dz * dz < reach * reach;
  };
  return walk_wall_path(x, r, active, si, di, path, at, ends, tangent, spread, near);
}

// ---------------------------------------------------------------------------------------------
// With the weight carried by two supports, is the grain at the bottom of their common curve?
bool Deposition::Impl::at_bottom(const Vec3& x, const Contacts& active) const {
  const Obstacle& a = active.item[0];
  const Obstacle& b = active.item[1];
  const Obstacle& s = a.kind == Obstacle::Kind::Sphere ? a : b;
  const Obstacle& o = a.kind == Obstacle::Kind::Sphere ? b : a;
  if (o.kind == Obstacle::Kind::Cylinder) {
    // Compare the height a little either way along the wall.
    const double phi = std::atan2(x.y(), x.x()), dphi = 1e-4;
    auto height = [&](double f) {
      Vec3 P(o.R * std::cos(f), o.R * std::sin(f), 0.0);
      const double h2 = (P.head<2>() - s.c.head<2>()).squaredNorm();
      return s.c.z() + std::sqrt(std::max(0.0, s.R * s.R - h2));
    };
    return height(phi + dphi) >= x.z() && height(phi - dphi) >= x.z();
  }
  Vec3 C;
  if (o.kind == Obstacle::Kind::Sphere) {
    const Vec3 axis = (o.c - s.c).normalized();
    const double D = (o.c - s.c).norm();
    C = s.c + axis * ((s.R * s.R - o.R * o.R + D * D) / (2.0 * D));
  } else {
    C = s.c + (o.R - o.c.dot(s.c)) * o.c;
  }
  return x.z() <= C.z() + 1e-12 * s.R;
}

Vec3 Deposition::Impl::tie_break(const Vec3& x, const Contacts& active, std::uint64_t salt) const {
  const std::uint64_t h = mix(salt);
  if (active.n == 1) {
    if (dimension == 2) return Vec3((h & 1) ? 1.0 : -1.0, 0.0, 0.0);
    const double angle = static_cast<double>(h >> 11) * 0x1.0p-53 * kTwoPi;
    return Vec3(std::cos(angle), std::sin(angle), 0.0);
  }
  const Vec3 n0 = active.item[0].normal(x), n1 = active.item[1].normal(x);
  Vec3 t = n0.cross(n1);
  if (t.norm() < 1e-12) return Vec3::Zero();
  t.normalize();
  return (h & 1) ? t : Vec3(-t);
}

// ---------------------------------------------------------------------------------------------
const Grain& Deposition::Impl::place(const Drop& drop) {
  const std::int64_t id = static_cast<std::int64_t>(grains.size()) + 1;
  const double r = drop.r;
  if (!(r > 0.0) || r > r_max * (1.0 + 1e-12)) {
    std::ostringstream why;
    why << "radius " << r << " is not in (0, r_max = " << r_max << "]";
    throw PlacementError(id, why.str());
  }
  if (!std::isfinite(drop.x) || (dimension == 3 && !std::isfinite(drop.y)) || std::isinf(drop.z)) {
    std::ostringstream why;
    why << "dropped at a non-finite position (" << drop.x << ", " << drop.y << ", " << drop.z << ")";
    throw PlacementError(id, why.str());
  }
  double px = drop.x, py = dimension == 3 ? drop.y : 0.0;
  if (wraps_x(container)) px = wrap_coordinate(px, container.size_x);
  if (wraps_y(container, dimension)) py = wrap_coordinate(py, container.size_y);
  const std::string misfit = drop_misfit(container, dimension, px, py, r);
  if (!misfit.empty()) throw PlacementError(id, "dropped outside the container: " + misfit);
  onto_footprint(container, dimension, px, py, r);
  if (mesh) return place_mesh(id, drop, px, py);

  container_walls(container, dimension, r, walls);
  Vec3 x(px, py, 0.0);
  if (container.kind == ContainerKind::Drum)
    drum_start(x, std::isnan(drop.z) ? top + r + 2.0 * r_max : drop.z, r);
  else
    x.z() = std::isnan(drop.z) ? top + r + 2.0 * r_max : free_start(px, py, drop.z, r);
  Contacts active;
  bool stable = false;
  int drum_stalls = 0;
  Vec3 blocked_tie = Vec3::Zero();  // the last tie-break roll that could not move the grain
  Vec3 last = x;
  int still = 0, still_contacts = 0;  // events in a row that left the grain where it was; most contacts then
  for (int event = 0; event < max_events && !stable; ++event) {
    if (active.overflow) throw too_many_contacts(id, x);
    // Wedged: the descent drops a support that the next event, not having moved the grain, finds again at
    // once (their tolerances disagree at round-off, next to a flat wall), round after round. With as many
    // contacts as the dimension touched in that place, the grain rests there.
    still = event > 0 && (x - last).squaredNorm() <= 1e-24 * r * r ? still + 1 : 0;
    still_contacts = still ? std::max(still_contacts, active.n) : active.n;
    last = x;
    if (still >= kWedgedEvents && still_contacts >= dimension) {
      stable = true;
      break;
    }
    bool tied = false;
    const Vec3 before_event = x;
    Vec3 normals[kMaxContacts];
    for (int i = 0; i < active.n; ++i) normals[i] = active.item[i].normal(x);
    const Descent descent = descend(normals, static_cast<std::size_t>(active.n));
    // Keep the loaded contacts, in order, in place (their keys are distinct already; `overflow` is false here).
    int kept = 0;
    for (int i = 0; i < active.n; ++i)
      if (descent.loaded[i]) {
        if (kept != i) active.item[kept] = active.item[i];
        ++kept;
      }
    active.n = kept;
    Vec3 d = descent.direction;
    // Gravity balanced by as many independent supports as the dimension: d is round-off.
    if (active.n >= dimension) d = Vec3::Zero();
    // On the drum's lowest line the wall's normal is vertical up to round-off: what is left of gravity
    // is round-off too (it would only start arcs of length ~1e-8 that end where they began).
    if (container.kind == ContainerKind::Drum && d.squaredNorm() < 1e-18) d = Vec3::Zero();

    if (d.isZero()) {
      bool on_floor = false;
      for (int i = 0; i < active.n; ++i) on_floor |= active.item[i].is_floor();
      const bool drum = container.kind == ContainerKind::Drum;
      if (on_floor || active.n >= dimension || (drum && drum_rest(x, active)) ||
          (!drum && active.n == 2 && at_bottom(x, active))) {
        stable = true;
        break;
      }
      // Balanced on a top (above one centre, or the top of a two-support curve): roll off it in
      // a direction fixed by the grain's id, so the result is deterministic.
      d = tie_break(x, active, static_cast<std::uint64_t>(id) * 1315423911ULL + event);
      if (d.isZero()) { stable = true; break; }
      // The last roll off this top was blocked at once (a wall or grain beside it): try the other side.
      if (!blocked_tie.isZero() && d.dot(blocked_tie) > 0.0) d = -d;
      tied = true;
    }
    if (!tied) blocked_tie = Vec3::Zero();

    int spheres = 0, planes = 0, cylinders = 0, drums = 0, si = -1, pi = -1, ci = -1, di = -1;
    for (int i = 0; i < active.n; ++i) {
      switch (active.item[i].kind) {
        case Obstacle::Kind::Sphere: ++spheres; si = si < 0 ? i : si; break;
        case Obstacle::Kind::Plane: ++planes; pi = i; break;
        case Obstacle::Kind::Cylinder: ++cylinders; ci = i; break;
        case Obstacle::Kind::Drum: ++drums; di = i; break;
      }
    }
    if (drums == 1) {
      if (spheres == 0) {
        // On the drum wall (and maybe an end wall): a circle about the axis, down to its lowest point.
        CircleArc arc;
        const Obstacle& w = active.item[di];
        arc.C = Vec3(0.0, x.y(), w.c.z());
        arc.rho = w.R;
        arc.u = (x - arc.C).normalized();
        arc.v = Vec3::UnitY().cross(arc.u);
        if (arc.v.dot(d) < 0.0) arc.v = -arc.v;
        const double t_low = std::atan2(-arc.v.z(), -arc.u.z());
        if (t_low <= 1e-12 || t_low >= M_PI) {  // on the lowest line already (up to round-off)
          stable = true;
          break;
        }
        arc.set_end(t_low, arc.lowest_direction());
        const Vec3 before = x;
        roll_on_arc(x, r, active, arc, walls);
        // Wedged a hair (~1e-8 rad) beside the lowest line against a grain that the descent, at round-off,
        // finds unloaded: the arc stops where it starts, again and again. The grain is at rest there.
        if ((x - before).squaredNorm() <= 1e-24 * r * r && ++drum_stalls >= 3) {
          stable = true;
          break;
        }
        continue;
      }
      if (spheres == 1 && planes == 0 && cylinders == 0 && dimension == 3) {
        if (roll_along_drum(x, r, active, si, di, d, walls)) stable = true;
        continue;
      }
    }
    if (spheres == 0) {
      fall(x, r, active, walls);
      continue;
    }
    const Obstacle& p = active.item[si];
    CircleArc arc;
    if (spheres == 1 && planes == 0 && cylinders == 0) {
      arc.C = p.c;
      arc.rho = p.R;
      arc.u = (x - p.c).normalized();
      arc.v = (d - d.dot(arc.u) * arc.u).normalized();
      // The support's equator, at the angle of (-v_z, u_z) when that is positive.
      if (positive_angle(-arc.v.z(), arc.u.z())) arc.set_end_towards(-arc.v.z(), arc.u.z());
      else arc.set_end(0.0, kArcStart);
    } else if (drums == 0 && ((spheres == 2 && planes == 0 && cylinders == 0) ||
                              (spheres == 1 && planes == 1 && cylinders == 0))) {
      int qi = pi;  // the second support: the plane, or the second sphere
      if (spheres == 2) {
        qi = si + 1;
        while (active.item[qi].kind != Obstacle::Kind::Sphere) ++qi;
      }
      const SupportCircle circle = support_circle(p, active.item[qi]);
      const Vec3 axis = circle.axis;
      arc.C = circle.C;
      arc.rho = circle.rho;
      Vec3 radial = x - arc.C;
      radial -= radial.dot(axis) * axis;
      if (arc.rho <= 1e-12 * r || radial.norm() <= 1e-12 * r) {
        // The supports meet in a point: nowhere to roll, the grain rests there.
        stable = true;
        break;
      }
      arc.u = radial.normalized();
      arc.v = axis.cross(arc.u);
      if (arc.v.dot(d) < 0.0) arc.v = -arc.v;
      arc.set_end_towards(-arc.u.z(), -arc.v.z());  // the lowest point of the circle
    } else if (spheres == 1 && cylinders == 1 && planes == 0 && drums == 0) {
      if (roll_along_cylinder(x, r, active, si, ci, d, walls)) stable = true;
      continue;
    } else {
      std::ostringstream why;
      why << "no rule for rolling on " << spheres << " grains, " << planes << " walls and " << cylinders
          << " cylinders" << (drums ? " and a drum wall" : "") << " at (" << x.x() << ", " << x.y() << ", " << x.z() << ")";
      throw PlacementError(id, why.str());
    }
    roll_on_arc(x, r, active, arc, walls);
    if (tied && (x - before_event).squaredNorm() <= 1e-24 * r * r) {
      // On top of two supports with both sides blocked (grains in one vertical plane against a
      // Hele-Shaw plate, say): it cannot roll off either way, so it rests there.
      if (!blocked_tie.isZero()) {
        stable = true;
        break;
      }
      blocked_tie = d;
    }
  }
  if (!stable) {
    std::ostringstream why;
    why << "no stable position after " << max_events << " events; last at (" << x.x() << ", " << x.y() << ", "
        << x.z() << ") with " << active.n << " contacts";
    const char* names[] = {"grain", "plane", "cylinder", "drum"};
    for (int i = 0; i < active.n; ++i) why << (i ? ", " : " (") << names[static_cast<int>(active.item[i].kind)];
    if (active.n) why << ")";
    throw PlacementError(id, why.str());
  }
  if (active.overflow) throw too_many_contacts(id, x);
  back_inside_walls(id, x, r);
  x = wrap_into_cell(container, dimension, x);
  if (!x.allFinite()) throw PlacementError(id, "the placement ended at a non-finite position");
  try {
    grid.insert(static_cast<std::int32_t>(grains.size()), x, r);
  } catch (const std::exception& e) {  // an escaped grain, or an open floor's grid out of budget
    throw PlacementError(id, e.what());
  }
  grains.push_back(Grain{x, r, drop.species});
  top = std::max(top, x.z() + r);
  return grains.back();
}

// ---------------------------------------------------------------------------------------------
// A mesh container: from above the mesh and the pile, onto the triangles and grains (mesh_placement.h).
const Grain& Deposition::Impl::place_mesh(std::int64_t id, const Drop& drop, double px, double py) {
  const double r = drop.r;
  if (!std::isnan(drop.z))
    throw PlacementError(id, "a start height is not supported in a mesh container (dynamic BTR needs another container)");
  const std::string misfit = mesh->footprint_misfit(px, py, r);
  if (!misfit.empty()) throw PlacementError(id, "dropped outside the container: " + misfit);
  const Vec3 start(px, py, std::max(top, container.mesh->hi.z()) + r + 2.0 * r_max);
  const Vec3 x = place_in_mesh(MeshEngine{grid, *mesh, r_max, max_events}, id, start, r);
  try {
    grid.insert(static_cast<std::int32_t>(grains.size()), x, r);
  } catch (const std::exception& e) {
    throw PlacementError(id, e.what());
  }
  grains.push_back(Grain{x, r, drop.species});
  top = std::max(top, x.z() + r);
  return grains.back();
}

// ---------------------------------------------------------------------------------------------
Deposition::Deposition(int dimension, const Container& container, double r_max, int max_events_per_grain) {
  if (dimension != 2 && dimension != 3) throw std::invalid_argument("dimension must be 2 or 3");
  if (!(r_max > 0.0)) throw std::invalid_argument("r_max must be positive");
  // The neighbour grid tells periodic images apart up to NeighbourGrid::kMaxImageShift periods; a query
  // reaches at most ~16 r_max, so a period of r_max / 256 or more is safe.
  auto check_period = [&](double period, const char* axis) {
    if (period * 256.0 >= r_max) return;
    std::ostringstream why;
    why << "the period " << period << " in " << axis << " is below r_max / 256 = " << r_max / 256.0
        << ": periodic images that far apart cannot be told apart";
    throw std::invalid_argument(why.str());
  };
  if (wraps_x(container)) check_period(container.size_x, "x");
  if (wraps_y(container, dimension)) check_period(container.size_y, "y");
  impl_ = std::make_unique<Impl>(dimension, container, r_max, max_events_per_grain);
}
Deposition::~Deposition() = default;
const Grain& Deposition::place(const Drop& drop) { return impl_->place(drop); }
std::int32_t Deposition::place_cluster(const ClusterDrop& drop) {
  Impl& d = *impl_;
  ClusterEngine engine{d.dimension, d.container, d.r_max, d.max_events, d.grains, d.grid, d.top, d.clusters};
  return place_rigid_cluster(engine, drop);
}
void Deposition::prefetch(const Drop& drop, int ahead) const {
  const Impl& d = *impl_;
  if (ahead < 0 || ahead > 2 || !(drop.r > 0.0)) return;
  d.grid.prefetch(drop.x, d.dimension == 3 ? drop.y : 0.0, drop.r + d.r_max,
                  std::isnan(drop.z) ? std::numeric_limits<double>::infinity() : drop.z + drop.r + d.r_max, 2 - ahead);
}
void Deposition::reserve(std::int64_t n, bool evenly) {
  Grains& g = impl_->grains;
  if (n <= 0 || static_cast<std::size_t>(n) <= g.capacity()) return;
  g.reserve(static_cast<std::size_t>(n));
  advise_large_pages(g.data(), g.capacity() * sizeof(Grain));
  if (evenly) impl_->grid.reserve(n - static_cast<std::int64_t>(g.size()));
}
const Grains& Deposition::grains() const { return impl_->grains; }
Grains Deposition::release() {
  Grains out = std::move(impl_->grains);
  impl_ = std::make_unique<Impl>(impl_->dimension, impl_->container, impl_->r_max, impl_->max_events);
  return out;
}
int Deposition::dimension() const { return impl_->dimension; }
const Container& Deposition::container() const { return impl_->container; }

}  // namespace btr
