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

#include "btr/placement/circle_arc.h"
#include "btr/placement/deposition.h"
#include "btr/placement/descent.h"
#include "btr/placement/grain_arc_event.h"
#include "btr/placement/mesh_index.h"
#include "btr/placement/neighbour_grid.h"
#include "btr/placement/obstacle.h"

namespace btr {
namespace {

// A contact partner: a fixed grain (one periodic image) or a triangle.
struct Partner {
  std::int64_t key = 0;  // sphere_key for grains, -1000 - t for triangle t
  int tri = -1;
  Vec3 c = Vec3::Zero();  // grain: centre
  double R = 0.0;         // grain: contact distance r + r_j
};

std::uint64_t mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

struct Walker {
  const MeshEngine& e;
  std::int64_t id;
  double r;
  std::vector<Partner> active;
  std::vector<Partner> near;  // candidates gathered about `gathered_at`
  Vec3 gathered_at = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  std::vector<int> tris;
  std::vector<Partner> entering;  // the partners a blocked step enters at its end
  std::vector<Partner> scratch;   // reused: the loaded contacts of a step, the hits of a fall
  std::vector<int> face_hits;     // reused: the faces a slide meets
  ArcEvent arc_event;

  double gap(const Partner& p, const Vec3& x) const {
    return p.tri >= 0 ? e.mesh.distance(p.tri, x) - r : (x - p.c).norm() - p.R;
  }
  Vec3 normal(const Partner& p, const Vec3& x) const {
    return p.tri >= 0 ? (x - e.mesh.closest(p.tri, x)).normalized() : (x - p.c).normalized();
  }
  bool has(std::int64_t key) const {
    for (const Partner& p : active)
      if (p.key == key) return true;
    return false;
  }
  [[noreturn]] void fail(const std::string& what, const Vec3& x) const {
    std::ostringstream why;
    why << what << " at (" << x.x() << ", " << x.y() << ", " << x.z() << ") in the mesh " << e.mesh.mesh().file;
    throw PlacementError(id, why.str());
  }

  // Adds a partner met at x; a triangle touching the grain where an active triangle does (their shared
  // edge or vertex, up to 1e-7 r) replaces it.
  void add(const Partner& p, const Vec3& x) {
    if (has(p.key)) return;
    if (p.tri >= 0) {
      const Vec3 q = e.mesh.closest(p.tri, x);
      for (Partner& a : active)
        if (a.tri >= 0 && (e.mesh.closest(a.tri, x) - q).norm() <= 1e-7 * r) {
          a = p;
          return;
        }
    }
    if (static_cast<int>(active.size()) >= kMaxContacts) {
      std::ostringstream why;
      why << "more than " << kMaxContacts << " simultaneous contacts";
      fail(why.str(), x);
    }
    active.push_back(p);
  }

  // Candidates for a path within r/2 of x: grains whose contact sphere and triangles whose offset surface
  // may reach it.
  void gather(const Vec3& x) {
    near.clear();
    const Vec3 reach = Vec3::Constant(2.0 * r + e.r_max);
    e.grid.visit_box(x - reach, x + reach, [&](std::int32_t i, const Vec3& c, double radius, int image) {
      Partner p;
      p.key = sphere_key(i, image), p.c = c, p.R = r + radius;
      near.push_back(p);
    });
    tris.clear();
    e.mesh.collect(x - Vec3::Constant(2.0 * r), x + Vec3::Constant(2.0 * r), tris);
    for (int t : tris) {
      Partner p;
      p.key = -1000 - static_cast<std::int64_t>(t), p.tri = t;
      near.push_back(p);
    }
    gathered_at = x;
  }

  // x moved back onto every active contact (Newton steps on their gaps, one or two contacts: a grain on
  // three is at rest); false when it does not converge.
  bool project(Vec3& x) const {
    const std::size_t k = active.size();
    if (k == 0 || k > 2) return k == 0;
    // 1e-14 r, or a few ulps of the coordinates where they are large against r (a big container)
    const double eps = 1e-14 * r + 1e-15 * x.cwiseAbs().maxCoeff();
    for (int it = 0; it < 40; ++it) {
      const double g0 = gap(active[0], x);
      const Vec3 n0 = normal(active[0], x);
      if (k == 1) {
        if (std::abs(g0) <= eps) return x.allFinite();
        x -= g0 * n0;
        continue;
      }
      const double g1 = gap(active[1], x);
      const Vec3 n1 = normal(active[1], x);
      if (std::max(std::abs(g0), std::abs(g1)) <= eps) return x.allFinite();
      // x -= N (N^T N)^-1 g with N = [n0 n1]
      const double c = n0.dot(n1), det = 1.0 - c * c;
      if (!(det > 1e-12)) return false;
      const double l0 = (g0 - c * g1) / det, l1 = (g1 - c * g0) / det;
      x -= l0 * n0 + l1 * n1;
    }
    return false;
  }

  Descent descent_at(const Vec3& x) const {
    Vec3 n[kMaxContacts];
    for (std::size_t i = 0; i < active.size(); ++i) n[i] = normal(active[i], x);
    return descend(n, active.size());
  }

  // What a grain that cannot move on holds: its contacts (grain or triangle, with their normals).
  std::string stuck(const char* what, const Vec3& x, const Vec3& d) const {
    std::ostringstream s;
    s << what << " (direction " << d.x() << ", " << d.y() << ", " << d.z() << "; contacts:";
    for (const Partner& p : active) {
      const Vec3 n = normal(p, x);
      s << " " << (p.tri >= 0 ? "triangle " + std::to_string(p.tri) : "grain " + std::to_string((p.key >> 30) + 1))
        << " normal (" << n.x() << ", " << n.y() << ", " << n.z() << ")";
    }
    s << ")";
    return s.str();
  }
  void fall(Vec3& x);
  int roll_exact(Vec3& x, const Vec3& d);
  int slide_exact(Vec3& x, const Vec3& d);
  bool face_contact(int t, const Vec3& x, Vec3& n, double& margin) const;
  bool roll_off_top(const Vec3& x, Vec3& d, std::uint64_t salt) const;
  Vec3 place(Vec3 x);
};

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

// Does triangle t touch the grain at x on its face (not an edge or a vertex)? Then its unit normal
// towards x and the in-plane distance of the contact point from the face's edges.
bool Walker::face_contact(int t, const Vec3& x, Vec3& n, double& margin) const {
  const auto& V = e.mesh.mesh().vertices;
  const auto& f = e.mesh.mesh().triangles[static_cast<std::size_t>(t)];
  n = (V[f[1]] - V[f[0]]).cross(V[f[2]] - V[f[0]]).normalized();
  const double h = n.dot(x - V[f[0]]);
  if (h < 0.0) n = -n;
  if (!n.allFinite() || std::abs(std::abs(h) - r) > 1e-9 * r) return false;
  margin = std::numeric_limits<double>::infinity();
  for (int j = 0; j < 3; ++j) {
    const Vec3 &a = V[f[j]], &b = V[f[(j + 1) % 3]], &c = V[f[(j + 2) % 3]];
    Vec3 m = n.cross(b - a).normalized();
    if (m.dot(c - a) < 0.0) m = -m;
    margin = std::min(margin, m.dot(x - a));
  }
  return margin > 1e-9 * r;
}

// On one or two grains and no triangle: the analytic engine's exact roll along the circular arc of its
// contacts (btr/placement/grain_arc_event.h), as far as no triangle can be met. The arc moves the grain
// at most rho t from its start (the chord is shorter than the arc), so on [0, t] it keeps off every
// triangle farther than r + rho t from the start. 0: a triangle is nearer than a walker step (the walker
// goes on); 1: moved (to an event, the arc's end, or as far as the triangles allow); 2: at rest at the
// lowest point of two grains' circle.
int Walker::roll_exact(Vec3& x, const Vec3& d) {
  const int n = static_cast<int>(active.size());
  if (n < 1 || n > 2) return 0;
  Obstacle sup[2];
  int face = -1;  // a face support (its offset plane), with a grain
  double face_margin = std::numeric_limits<double>::infinity();
  for (int k = 0; k < n; ++k) {
    sup[k].key = active[k].key;
    if (active[k].tri >= 0) {
      if (n != 2 || face >= 0 || !face_contact(active[k].tri, x, sup[k].c, face_margin)) return 0;
      face = k;
      sup[k].kind = Obstacle::Kind::Plane;
      sup[k].R = sup[k].c.dot(e.mesh.closest(active[k].tri, x)) + r;  // the centre's plane n.x = R
      continue;
    }
    sup[k].kind = Obstacle::Kind::Sphere;
    sup[k].c = active[k].c, sup[k].R = active[k].R;
  }
  CircleArc arc;
  if (n == 1) {
    arc.C = sup[0].c;
    arc.rho = sup[0].R;
    arc.u = (x - sup[0].c).normalized();
    arc.v = (d - d.dot(arc.u) * arc.u).normalized();
    arc.t_end = std::max(0.0, std::atan2(arc.u.z(), -arc.v.z()));  // the support's equator
  } else {
    Vec3 axis;
    if (face < 0) {
      const double D = (sup[1].c - sup[0].c).norm();
      axis = (sup[1].c - sup[0].c) / D;
      const double s = (sup[0].R * sup[0].R - sup[1].R * sup[1].R + D * D) / (2.0 * D);
      arc.C = sup[0].c + s * axis;
      arc.rho = std::sqrt(std::max(0.0, sup[0].R * sup[0].R - s * s));
    } else {  // the circle where the grain's contact sphere meets the face's offset plane
      const Obstacle &p = sup[1 - face], &w = sup[face];
      axis = w.c;
      const double s = w.R - w.c.dot(p.c);
      arc.C = p.c + s * axis;
      arc.rho = std::sqrt(std::max(0.0, p.R * p.R - s * s));
    }
    Vec3 radial = x - arc.C;
    radial -= radial.dot(axis) * axis;
    if (arc.rho <= 1e-12 * r || radial.norm() <= 1e-12 * r) return 0;
    arc.u = radial.normalized();
    arc.v = axis.cross(arc.u);
    if (arc.v.dot(d) < 0.0) arc.v = -arc.v;
    double t_low = std::atan2(-arc.v.z(), -arc.u.z());
    if (t_low <= 0.0) t_low += 2.0 * M_PI;
    if (t_low > M_PI + 1e-6) return 0;  // d does not go down the circle (round-off at its lowest point)
    arc.t_end = t_low;
  }
  if (!arc.u.allFinite() || !arc.v.allFinite() || !(arc.rho > 0.0)) return 0;
  const Vec3 x0 = arc.at(0.0);
  // The contact point stays on the face while its projection, which moves no more than the centre,
  // keeps inside the face's edges.
  double clear = face >= 0 ? -1.0 : e.mesh.clearance(x0) - r;
  if (clear * (1.0 - 1e-9) < arc.rho * arc.t_end) {
    Vec3 lo, hi;
    arc.bounds(lo, hi);
    lo = lo.cwiseMin(x0) - Vec3::Constant(r), hi = hi.cwiseMax(x0) + Vec3::Constant(r);
    tris.clear();
    e.mesh.collect(lo, hi, tris);
    clear = std::numeric_limits<double>::infinity();
    for (int t : tris)
      if (face < 0 || t != active[face].tri) clear = std::min(clear, e.mesh.distance(t, x0) - r);
    clear = std::min(clear, face_margin);
  }
  if (clear < 0.1 * r) return 0;
  CircleArc part = arc;
  const bool whole = clear * (1.0 - 1e-9) >= arc.rho * arc.t_end;
  if (!whole) part.t_end = clear * (1.0 - 1e-9) / arc.rho;
  first_grain_event(e.grid, r, e.r_max, sup, n, part, arc_event);
  x = arc.at(arc_event.t);
  if (arc_event.lift_off >= 0) active.erase(active.begin() + arc_event.lift_off);
  for (const Obstacle& o : arc_event.hits) {
    Partner p;
    p.key = o.key, p.c = o.c, p.R = o.R;
    add(p, x);
  }
  if (whole && arc_event.lift_off < 0 && arc_event.hits.empty()) {
    if (n == 2) return 2;
    active.clear();  // at the support's equator it carries nothing: the grain falls
  }
  return 1;
}

// On one face, or two faces meeting in a groove, and nothing else: the path is a straight line down the
// face (or the groove), so the slide is exact: as far as the face's edges (where the walker takes over
// the next triangle), up to the first grain met (btr/placement/grain_arc_event.h), and no farther than
// any other triangle allows: one farther than r + s from the start is not met within s, nor one whose
// plane the line keeps more than r from. 0: not on faces only, or too short a slide for it (the walker
// goes on); 1: moved.
int Walker::slide_exact(Vec3& x, const Vec3& d) {
  const int n = static_cast<int>(active.size());
  if (n < 1 || n > 2) return 0;
  const auto& V = e.mesh.mesh().vertices;
  Vec3 nrm[2];
  for (int k = 0; k < n; ++k) {
    if (active[k].tri < 0) return 0;
    const auto& f = e.mesh.mesh().triangles[static_cast<std::size_t>(active[k].tri)];
    Vec3 m = (V[f[1]] - V[f[0]]).cross(V[f[2]] - V[f[0]]).normalized();
    const double h = m.dot(x - V[f[0]]);
    if (h < 0.0) m = -m;
    if (!m.allFinite() || std::abs(std::abs(h) - r) > 1e-9 * r) return 0;  // touched at an edge or vertex
    nrm[k] = m;
  }
  Vec3 g;
  if (n == 1) {
    g = Vec3(0.0, 0.0, -1.0) + nrm[0].z() * nrm[0];
  } else {
    g = nrm[0].cross(nrm[1]);
    if (g.z() > 0.0) g = -g;
  }
  if (g.norm() < 1e-6) return 0;
  g.normalize();
  if (g.z() > -1e-6 || g.dot(d) < 0.999) return 0;
  // Where the contact point leaves an active face: its in-plane distance from each edge, shrinking at
  // the rate g . (inward normal of the edge).
  double s_max = std::numeric_limits<double>::infinity();
  for (int k = 0; k < n; ++k) {
    const auto& f = e.mesh.mesh().triangles[static_cast<std::size_t>(active[k].tri)];
    for (int j = 0; j < 3; ++j) {
      const Vec3 &a = V[f[j]], &b = V[f[(j + 1) % 3]], &c = V[f[(j + 2) % 3]];
      Vec3 m = nrm[k].cross(b - a).normalized();
      if (m.dot(c - a) < 0.0) m = -m;
      const double inside = m.dot(x - a), rate = m.dot(g);
      if (!(inside > 1e-9 * r)) return 0;  // on the edge: the walker decides which triangle
      if (rate < 0.0) s_max = std::min(s_max, inside / -rate);
    }
  }
  if (!std::isfinite(s_max)) return 0;
  const double s_exit = s_max, past = 1e-6 * r;  // past: how far a slide goes over onto a flat neighbour
  s_max = std::min(s_max + past, 8.0 * r);  // a long slide in several moves: each gathers the triangles of a short box
  const Vec3 x0 = x, x1 = x0 + s_max * g;
  tris.clear();
  e.mesh.collect(x0.cwiseMin(x1) - Vec3::Constant(r), x0.cwiseMax(x1) + Vec3::Constant(r), tris);
  const double reach = r * (1.0 + 1e-9);
  int flat_next = -1;  // a neighbour in the plane of the face slid on that the path enters past its edge
  double tri_s = std::numeric_limits<double>::infinity();  // the first face met (its plane, inside it)
  std::vector<int>& tri_hits = face_hits;
  tri_hits.clear();
  for (int t : tris) {
    if (t == active[0].tri || (n == 2 && t == active[1].tri)) continue;
    double safe = e.mesh.distance(t, x0) - reach;
    const auto& f = e.mesh.mesh().triangles[static_cast<std::size_t>(t)];
    const Vec3 m = (V[f[1]] - V[f[0]]).cross(V[f[2]] - V[f[0]]).normalized();
    const double h = m.dot(x0 - V[f[0]]), rate = m.dot(g);
    if (n == 1 && std::abs(std::abs(m.dot(nrm[0])) - 1.0) <= 1e-12 && std::abs(std::abs(h) - r) <= 1e-9 * r) {
      // In the same plane, on the grain's side: the centre keeps r from that plane, so from t. The path
      // goes on over t when it enters t's face past the edge.
      Vec3 nn;
      double margin;
      if (flat_next < 0 && face_contact(t, x0 + (s_exit + past) * g, nn, margin)) flat_next = t;
      continue;
    }
    if (m.allFinite() && std::abs(h) > reach) {
      if (h * rate >= 0.0) continue;  // the line keeps at least |h| from the triangle's plane
      // Where the line comes within r of the plane; if the nearest point of the plane lies inside the
      // face there, the face is met there (its edges and vertices are no nearer than its plane).
      const double s_touch = (std::abs(h) - r) / std::abs(rate);
      Vec3 nn;
      double margin;
      if (s_touch <= s_max && face_contact(t, x0 + s_touch * g, nn, margin)) {
        if (s_touch < tri_s - 1e-13 * r) tri_s = s_touch, tri_hits.clear();
        if (s_touch <= tri_s + 1e-13 * r) tri_hits.push_back(t);
        continue;
      }
      safe = std::max(safe, (std::abs(h) - reach) / std::abs(rate));
    }
    s_max = std::min(s_max, safe);
  }
  // Past the edge only onto a flat neighbour; otherwise to the edge, where the walker takes over.
  const bool over = flat_next >= 0 && s_max >= s_exit + past && tri_s > s_exit + past;
  s_max = over ? s_exit + past : std::min(s_max, s_exit);
  const bool face_met = tri_s <= s_max;  // an exact event: no shortest slide for it
  if (face_met) s_max = tri_s;
  else if (!(s_max >= 0.1 * r)) return 0;
  const double s = first_grain_on_segment(e.grid, r, e.r_max, x0, g, s_max, nullptr, 0, arc_event.hits);
  x = x0 + s * g;
  if (face_met && s >= tri_s - 1e-13 * r)
    for (int t : tri_hits) {
      Partner p;
      p.key = -1000 - static_cast<std::int64_t>(t), p.tri = t;
      add(p, x);
    }
  if (over && arc_event.hits.empty()) {
    active[0].tri = flat_next;
    active[0].key = -1000 - static_cast<std::int64_t>(flat_next);
  }
  for (const Obstacle& o : arc_event.hits) {
    Partner p;
    p.key = o.key, p.c = o.c, p.R = o.R;
    add(p, x);
  }
  return 1;
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
    // cannot be kept (3). Inside a blocked step only the partners entered at its end are watched (one
    // entered and left again within a step of r/10 would be a graze of depth ~1e-3 r at most).
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
    if (why == 0) {
      x = p1;
      h = std::min(h_max, 2.0 * h);
      continue;
    }
    entering.clear();
    if (why == 1)
      for (const Partner& q : near)
        if (!has(q.key) && gap(q, p1) < -tol) entering.push_back(q);
    watched = &entering;
    double s0 = 0.0, s1 = 1.0;
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
    // A partner the step only grazed (entered and left before its end) may hold the point found: then
    // again, watching every partner near, so the grain stops where it first meets one.
    bool grazed = false;
    for (const Partner& q : near) grazed |= !has(q.key) && gap(q, p0) < -tol;
    if (grazed) {
      watched = &near;
      s0 = 0.0, s1 = 1.0, p0 = x;
      why = blocked(1.0, p1);
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

}  // namespace

Vec3 place_in_mesh(const MeshEngine& engine, std::int64_t id, Vec3 x, double r) {
  Walker w{engine, id, r, {}, {}, Vec3::Constant(std::numeric_limits<double>::quiet_NaN()), {}, {}, {}, {}, {}};
  x = w.place(x);
  if (!x.allFinite()) throw PlacementError(id, "the placement ended at a non-finite position");
  if (engine.mesh.crossings_below(x.x(), x.y(), x.z()) % 2 == 0)
    w.fail("came to rest outside the mesh (over its rim, or below an opening)", x);
  return x;
}

}  // namespace btr
