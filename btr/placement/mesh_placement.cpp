// The placement of one grain in a mesh container (docs/design.md, "Mesh containers"). The state is the
// centre x and its active contacts, as in btr/placement/deposition.cpp; each event asks where gravity
// pushes the grain (descend) and moves it. Where no triangle can be met the move is exact in one event
// (roll_exact: on grains, or a grain and a face, along a circle; slide_exact: straight down a face or a
// groove of two); otherwise, and for edges and vertices, the walker steps:
//   no contact     a vertical fall, solved exactly against grains and triangles;
//   one or two     along the set of positions keeping those contacts, in steps of at most r/10 (each
//                  projected back onto the contacts, so the path lies exactly on them: a meridian of a
//                  grain or vertex sphere, a line on a face, the circle or curve of two contacts), an event
//                  inside a step located by bisection: a new contact, a support lifting off;
//   balanced       at rest on three supports, on a horizontal face, at the lowest point of a two-support
//                  curve; on a top (a grain, a vertex, an edge) it rolls off in a direction fixed by a hash.
// A triangle met where another active triangle already touches the grain at the same point (rolling
// over their shared edge or vertex) takes that triangle's place instead of adding a second contact.
#include "btr/placement/mesh_placement.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include "btr/placement/mesh_walker.h"
#include "btr/placement/path_graze.h"

namespace btr {
namespace mesh_walk {
namespace {

std::uint64_t mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace

// Straight down to the highest contact below, exactly: z_j + sqrt((r + r_j)^2 - h^2) for a grain, the
// first height at distance r from a triangle (MeshIndex::fall_contact).
void Walker::fall(Vec3& x) {
  const double tol = 1e-12 * r;
  double best = -std::numeric_limits<double>::infinity();
  std::vector<Partner>& hits = scratch;
  hits.clear();
  auto offer = [&](double z, const Partner& p) {
    if (z > best + tol) {
      best = z;
      hits.clear();
    }
    if (z >= best - tol) hits.push_back(p);
  };
  const double reach = r + e.r_max;
  e.grid.visit_column_down(
      x.x(), x.y(), reach, x.z() + reach, [&](double layer_top) { return layer_top + reach > best; },
      [&](std::int32_t i, const Vec3& c, double radius, int image) {
        const double R = r + radius;
        const double dx = x.x() - c.x(), dy = x.y() - c.y();
        const double s = R * R - dx * dx - dy * dy;
        if (s <= 1e-12 * R * R) return;
        const double z_hit = c.z() + std::sqrt(s);
        if (z_hit > x.z() + tol) return;
        Partner p;
        p.key = sphere_key(i, image), p.c = c, p.R = R;
        offer(z_hit, p);
      });
  // A triangle is met at most r above its highest point: those lower than the grain met are skipped.
  const double z_lo = std::isfinite(best) ? best - r - 2.0 * tol : -std::numeric_limits<double>::infinity();
  tris.clear();
  e.mesh.collect(Vec3(x.x() - r, x.y() - r, z_lo), Vec3(x.x() + r, x.y() + r, x.z() + r), tris);
  for (int t : tris) {
    const double z_hit = e.mesh.fall_contact(t, x, r, best - 2.0 * tol);
    if (std::isnan(z_hit)) continue;
    Partner p;
    p.key = -1000 - static_cast<std::int64_t>(t), p.tri = t;
    offer(z_hit, p);
  }
  if (hits.empty())
    fail("falls out of the mesh: no triangle or grain below it (an open outlet, or over its rim)", x);
  x.z() = best;
  for (const Partner& p : hits) add(p, x);
}

// Balanced on a top (a grain, a vertex, an edge, the top of a two-support curve): the first of a few
// directions, fixed by a hash of the grain, along which a small move keeping the contacts goes down.
// None (a horizontal face, the bottom of a curve): false, the grain is at rest.
bool Walker::roll_off_top(const Vec3& x, Vec3& d, std::uint64_t salt) const {
  const std::uint64_t h = mix(salt);
  Vec3 dirs[4];
  int n = 0;
  if (active.size() == 1) {
    const double angle = static_cast<double>(h >> 11) * 0x1.0p-53 * 2.0 * M_PI;
    const Vec3 u(std::cos(angle), std::sin(angle), 0.0), v(-u.y(), u.x(), 0.0);
    dirs[n++] = u, dirs[n++] = -u, dirs[n++] = v, dirs[n++] = -v;
  } else if (active.size() == 2) {
    Vec3 t = normal(active[0], x).cross(normal(active[1], x));
    if (t.norm() < 1e-12) return false;
    t.normalize();
    if (h & 1) t = -t;
    dirs[n++] = t, dirs[n++] = -t;
  }
  const double delta = 1e-5 * r;
  for (int k = 0; k < n; ++k) {
    Vec3 y = x + delta * dirs[k];
    if (!project(y)) continue;
    if (y.z() < x.z() - 1e-9 * delta) {
      d = dirs[k];
      return true;
    }
  }
  return false;
}

// The step from x (s = 0) along d by h, each point projected onto the contacts (project): the first s in (0, sb]
// where a partner not in contact is entered deeper than 1e-9 r (the self-check's overlap tolerance; a shallower
// graze is a tangency), between x and xb (the point at sb), both clear; NaN when every partner is proven clear
// there (first_graze_of, btr/placement/path_graze.h). Partners within 1e-9 r at x or xb are left out: the
// triangles sharing a contact's edge or vertex touch the grain along the whole step, and the partner a
// bisected step meets is touched at its end.
// - Travel: the centre moves at most kPathSpeed h |ds| over ds. The line x + s h d lies outside the reach of
//   each contact (a convex set: a grain's sphere, a face's slab, an edge's cylinder, a vertex's sphere), and
//   the projection onto one of them, or onto the circle where two spheres, or a sphere and a face, meet,
//   shortens distances; Newton's projection onto the other curves of two contacts (an edge's cylinder with a
//   second contact) lies within O(h^2) of that, which the margin covers (32 samples of every step of the tall
//   hopper's 1e5 grains, docs/mesh: at most 1.0000001).
// - Sag: a partner's gap g(s) has g'' = P'^T H P' + grad g . P'', H the Hessian of the distance to a grain's
//   centre or a triangle, at most 1 / (r + g) <= 1 / (0.9 r) where the ends are clear (g >= -0.055 r between
//   them), and |P''| at most h^2 kappa, kappa the path's curvature: a contact's normal curvature on one (1 / R
//   on a grain, R = r + r_j; 1 / r about an edge or a vertex; 0 over a face; the exact second derivative is
//   h^2 / R at most there), and the sum of the two's over sin(theta) on two, theta the angle between their
//   normals (0 for two faces: a straight groove); taken twice over for the parameter's uneven speed.
// A bound on the curvature of the path between x and xb, along which the centre travels at most `travel` (the
// sag bound above). A contact's normal curvature: a grain's 1 / R; a triangle's 0 where the grain lies over its
// face at both ends (the slab between is convex), 1 / r about an edge or a vertex. On two contacts, their sum
// over the sine of the normals' angle, which turns by at most travel / r for each.
double Walker::path_curvature(const Vec3& x, const Vec3& xb, double travel) const {
  Vec3 nx[2], nb[2];
  double kappa = 0.0;
  for (std::size_t i = 0; i < active.size(); ++i) {
    const Partner& a = active[i];
    nx[i] = normal(a, x), nb[i] = normal(a, xb);
    if (a.tri < 0) kappa += 1.0 / a.R;
    else {
      const Vec3& n = e.mesh.normal(a.tri);
      const bool face = std::abs(nx[i].dot(n)) >= 1.0 - 1e-12 && std::abs(nb[i].dot(n)) >= 1.0 - 1e-12;
      kappa += face ? 0.0 : 1.0 / r;
    }
  }
  if (active.size() < 2 || kappa == 0.0) return kappa;
  const double sin_low = std::min(nx[0].cross(nx[1]).norm(), nb[0].cross(nb[1]).norm()) - 2.0 * travel / r;
  return sin_low > 0.0 ? kappa / sin_low : std::numeric_limits<double>::infinity();
}

double Walker::step_graze(const Vec3& x, const Vec3& xb, double h, const Vec3& d, double sb) const {
  constexpr double kPathSpeed = 1.1;
  auto gap_of = [&](const Partner& q, const Vec3& p) {
    return has(q.key) ? std::numeric_limits<double>::infinity() : gap(q, p);
  };
  auto at = [&](double s) {
    Vec3 p = x + s * h * d;
    return project(p) ? p : Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  };
  auto spread = [&](double, double ds) { return kPathSpeed * h * std::abs(ds); };
  // The bound on the gap's second derivative, taken when a partner first needs it (most steps clear every
  // partner by the travel bound).
  double M = -1.0;
  auto sag = [&](double lo, double hi) {
    if (M < 0.0) M = h * h * (kPathSpeed * kPathSpeed / (0.9 * r) + 2.0 * path_curvature(x, xb, kPathSpeed * h * sb));
    return M * (hi - lo) * (hi - lo) / 8.0;
  };
  return first_graze_of(0.0, sb, x, xb, near, gap_of, 1e-9 * r, 1e-9 * r, at, spread, sag);
}

Vec3 Walker::place(Vec3 x) {
  const double tol = 1e-10 * r;  // a gap below -tol is an entry into a partner
  const double h_max = 0.1 * r;
  double h = h_max;
  const long budget = static_cast<long>(e.max_events) * 100L;
  for (long step = 0; step < budget; ++step) {
    // Release the contacts that carry nothing.
    const Descent desc = descent_at(x);
    std::vector<Partner>& loaded = scratch;
    loaded.clear();
    for (std::size_t i = 0; i < active.size(); ++i)
      if (desc.loaded[i]) loaded.push_back(active[i]);
    active.swap(loaded);
    if (active.size() >= 3) return x;
    Vec3 d = desc.direction;
    if (active.empty()) {
      fall(x);
      h = h_max;
      continue;
    }
    if (d.norm() < 1e-12) {
      if (!roll_off_top(x, d, static_cast<std::uint64_t>(id) * 1315423911ULL + static_cast<std::uint64_t>(step)))
        return x;
    }
    d.normalize();
    int exact = roll_exact(x, d);
    if (exact == 0) exact = slide_exact(x, d);
    if (exact == 2) return x;
    if (exact == 1) {
      h = h_max;
      continue;
    }
    if (!(gathered_at.allFinite()) || (x - gathered_at).norm() > 0.5 * r) gather(x);
    Vec3 y = x + h * d;
    if (!project(y) || !(y.z() < x.z()) || (y - x).norm() > 2.0 * h) {
      // Past the lowest point of the path, or off a curve that turns within the step: a shorter step.
      h *= 0.5;
      if (h < 1e-10 * r) {
        if (active.size() == 2) return x;  // the lowest point of the two contacts' curve
        fail(stuck("cannot go down along its contacts", x, d), x);
      }
      continue;
    }
    // The first point of the step where a partner is entered (1), a support unloads (2) or the contacts
    // cannot be kept (3). Inside a blocked step the bisection watches the partners entered at its end; one
    // entered and left again before it is found by the graze search.
    const std::vector<Partner>* watched = &near;
    auto blocked = [&](double s, Vec3& p) {
      p = x + s * h * d;
      if (!project(p)) return 3;
      for (const Partner& q : *watched)
        if (!has(q.key) && gap(q, p) < -tol) return 1;
      const Descent dd = descent_at(p);
      for (std::size_t i = 0; i < active.size(); ++i)
        if (!dd.loaded[i]) return 2;
      return 0;
    };
    Vec3 p1;
    int why = blocked(1.0, p1);
    double s1 = 1.0;
    if (why == 0) {
      // Both ends clear: a partner entered and left between them is found by the graze search, which then
      // stands for the step's end (its own test there decides).
      s1 = step_graze(x, p1, h, d, 1.0);
      if (std::isnan(s1)) {
        x = p1;
        h = std::min(h_max, 2.0 * h);
        continue;
      }
      why = blocked(s1, p1);
    }
    entering.clear();
    if (why == 1)
      for (const Partner& q : near)
        if (!has(q.key) && gap(q, p1) < -tol) entering.push_back(q);
    watched = &entering;
    double s_end = s1;
    double s0 = 0.0;
    Vec3 p0 = x;
    auto bisect = [&] {
      for (int it = 0; it < 60; ++it) {
        const double sm = 0.5 * (s0 + s1);
        Vec3 pm;
        const int w = blocked(sm, pm);
        if (w) s1 = sm, p1 = pm, why = w;
        else s0 = sm, p0 = pm;
      }
    };
    bisect();
    // A partner the step only grazed (entered and left before the point found) may hold that point, or lie
    // between it and the step's start (the graze search): then again, watching every partner near, so the
    // grain stops where it first meets one.
    bool grazed = false;
    for (const Partner& q : near) grazed |= !has(q.key) && gap(q, p0) < -tol;
    if (!grazed && s0 > 0.0) {
      const double s = step_graze(x, p0, h, d, s0);
      if (!std::isnan(s)) grazed = true, s_end = s;
    }
    if (grazed) {
      watched = &near;
      s0 = 0.0, s1 = s_end, p0 = x;
      why = blocked(s_end, p1);
      bisect();
    }
    x = p0;
    if (why == 1) {
      // The partners entered join (or replace a triangle touching at the same point).
      for (const Partner& q : *watched)
        if (!has(q.key) && gap(q, p1) < -tol) add(q, x);
    } else if (why == 2) {
      x = p1;  // just past the lift-off: the next descent releases the support
    } else {
      h *= 0.5;
      if (h < 1e-10 * r) fail(stuck("cannot keep its contacts along its path", x, d), x);
      continue;
    }
    h = h_max;
  }
  std::ostringstream why;
  why << "no stable position after " << budget << " steps (event budget " << e.max_events << " x 100) with "
      << active.size() << " contacts";
  fail(why.str(), x);
}

}  // namespace mesh_walk

Vec3 place_in_mesh(const MeshEngine& engine, std::int64_t id, Vec3 x, double r) {
  mesh_walk::Walker w{engine, id, r, {}, {}, Vec3::Constant(std::numeric_limits<double>::quiet_NaN()), {}, {}, {}, {}, {}};
  // The walker's lists keep their storage from one grain to the next (allocating them per grain cost more
  // than some of the moves).
  thread_local mesh_walk::Walker::Lists lists;
  w.take(lists);
  struct Return {
    mesh_walk::Walker& w;
    mesh_walk::Walker::Lists& lists;
    ~Return() { w.give(lists); }
  } give_back{w, lists};
  x = w.place(x);
  if (!x.allFinite()) throw PlacementError(id, "the placement ended at a non-finite position");
  if (engine.mesh.crossings_below(x.x(), x.y(), x.z()) % 2 == 0)
    w.fail("came to rest outside the mesh (over its rim, or below an opening)", x);
  return x;
}

}  // namespace btr
