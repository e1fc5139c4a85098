// The exact moves of a grain in a mesh container where no triangle can be met (docs/design.md, "Mesh
// containers"): the analytic engine's arcs on grains, or on a grain and a face, and straight slides down a
// face or a groove; each goes only as far as the triangles allow, the walker takes the rest.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "btr/placement/circle_arc.h"
#include "btr/placement/mesh_walker.h"

namespace btr::mesh_walk {

// Does triangle t touch the grain at x (its plane at r from x, up to tol) on its face (not an edge or a
// vertex)? Then its unit normal towards x and the in-plane distance of the contact point from the face's edges.
bool Walker::face_contact(int t, const Vec3& x, Vec3& n, double& margin, double tol) const {
  const auto& V = e.mesh.mesh().vertices;
  const auto& f = e.mesh.mesh().triangles[static_cast<std::size_t>(t)];
  n = (V[f[1]] - V[f[0]]).cross(V[f[2]] - V[f[0]]).normalized();
  const double h = n.dot(x - V[f[0]]);
  if (h < 0.0) n = -n;
  if (!n.allFinite() || std::abs(std::abs(h) - r) > tol) return false;
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
      if (n != 2 || face >= 0 || !face_contact(active[k].tri, x, sup[k].c, face_margin, 1e-9 * r)) return 0;
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
    // Two grains' contact spheres, or a grain's and the face's offset plane.
    const SupportCircle circle = face < 0 ? support_circle(sup[0], sup[1]) : support_circle(sup[1 - face], sup[face]);
    const Vec3 axis = circle.axis;
    arc.C = circle.C;
    arc.rho = circle.rho;
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
  // keeps inside the face's edges. Otherwise the cheap bound first; the triangles are measured when it does
  // not cover the arc or is below the walker's r/10 (so what follows depends on the geometry only, not on
  // the bound's cells).
  double clear = face >= 0 ? -1.0 : e.mesh.clearance(x0) - r;
  if (clear * (1.0 - 1e-9) < arc.rho * arc.t_end || clear < 0.1 * r) {
    Vec3 lo, hi;
    arc.bounds(lo, hi);
    lo = lo.cwiseMin(x0) - Vec3::Constant(r), hi = hi.cwiseMax(x0) + Vec3::Constant(r);
    tris.clear();
    e.mesh.collect(lo, hi, tris);
    clear = std::numeric_limits<double>::infinity();
    for (int t : tris)  // (a triangle whose distance bound exceeds the nearest so far is not measured)
      if ((face < 0 || t != active[face].tri) && e.mesh.distance_bound(t, x0) - r < clear + 1e-9 * r)
        clear = std::min(clear, e.mesh.distance(t, x0) - r);
    clear = std::min(clear, face_margin);
  }
  if (clear < 0.1 * r) return 0;
  CircleArc part = arc;
  const bool whole = clear * (1.0 - 1e-9) >= arc.rho * arc.t_end;
  if (!whole) part.set_end(clear * (1.0 - 1e-9) / arc.rho, ArcDirection::unknown());
  Contacts supports;
  for (int k = 0; k < n; ++k) supports.add(sup[k]);
  const Event ev = first_grain_event(e.grid, r, e.r_max, supports, part);
  x = arc.at(ev.t, ev.direction);
  if (ev.hits.overflow) {
    std::ostringstream why;
    why << "more than " << kMaxContacts << " simultaneous contacts";
    fail(why.str(), x);
  }
  if (ev.lift_off >= 0) active.erase(active.begin() + ev.lift_off);
  for (int i = 0; i < ev.hits.n; ++i) {
    const Obstacle& o = ev.hits.item[i];
    Partner p;
    p.key = o.key, p.c = o.c, p.R = o.R;
    add(p, x);
  }
  if (whole && ev.lift_off < 0 && ev.hits.n == 0) {
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
  // A neighbour counts as in the face's plane up to the rounding of the mesh's coordinates: the two triangles
  // of a flat CAD panel are coplanar only to that (4e-6 r in the tall hopper), and stepping the walker over
  // every such diagonal cost more than the exact moves around it.
  const double flat_tol = std::max(1e-9 * r, 4.0 * e.mesh.vertex_roundoff());
  int flat_next = -1;  // a neighbour in the plane of the face slid on that the path enters past its edge
  Vec3 flat_normal;    // its unit normal towards the grain past the edge
  double tri_s = std::numeric_limits<double>::infinity();  // the first face met (its plane, inside it)
  std::vector<int>& tri_hits = face_hits;
  tri_hits.clear();
  for (int t : tris) {
    if (t == active[0].tri || (n == 2 && t == active[1].tri)) continue;
    double safe = e.mesh.distance(t, x0) - reach;
    const auto& f = e.mesh.mesh().triangles[static_cast<std::size_t>(t)];
    const Vec3 m = (V[f[1]] - V[f[0]]).cross(V[f[2]] - V[f[0]]).normalized();
    const double h = m.dot(x0 - V[f[0]]), rate = m.dot(g);
    // Towards the grain, t's normal is the face's (not a parallel face on the far side of the grain).
    const bool facing = (h > 0.0 ? m : Vec3(-m)).dot(nrm[0]) >= 1.0 - 1e-12;
    if (n == 1 && facing && std::abs(std::abs(h) - r) <= flat_tol) {
      // In the same plane (up to flat_tol), on the grain's side: the centre keeps r from that plane, so from
      // t. The path goes on over t when it enters t's face past the edge.
      double margin;
      if (flat_next < 0 && face_contact(t, x0 + (s_exit + past) * g, flat_normal, margin, flat_tol)) flat_next = t;
      continue;
    }
    if (m.allFinite() && std::abs(h) > reach) {
      if (h * rate >= 0.0) continue;  // the line keeps at least |h| from the triangle's plane
      // Where the line comes within r of the plane; if the nearest point of the plane lies inside the
      // face there, the face is met there (its edges and vertices are no nearer than its plane).
      const double s_touch = (std::abs(h) - r) / std::abs(rate);
      Vec3 nn;
      double margin;
      if (s_touch <= s_max && face_contact(t, x0 + s_touch * g, nn, margin, 1e-9 * r)) {
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
  const double s = first_grain_on_segment(e.grid, r, e.r_max, x0, g, s_max, nullptr, 0, segment_hits);
  x = x0 + s * g;
  if (face_met && s >= tri_s - 1e-13 * r)
    for (int t : tri_hits) {
      Partner p;
      p.key = -1000 - static_cast<std::int64_t>(t), p.tri = t;
      add(p, x);
    }
  if (over && segment_hits.empty()) {
    // Onto the neighbour's own plane (a move of at most flat_tol along its normal), unless a grain is that near.
    // x is the point face_contact judged (the slide went the whole s_exit + past).
    const Vec3& m = flat_normal;
    const double lift = r - m.dot(x - V[e.mesh.mesh().triangles[static_cast<std::size_t>(flat_next)][0]]);
    if (lift != 0.0) {
      const Vec3 way = lift > 0.0 ? m : Vec3(-m);
      first_grain_on_segment(e.grid, r, e.r_max, x, way, std::abs(lift), nullptr, 0, segment_hits);
      if (!segment_hits.empty()) {  // to the edge instead, where the walker takes over
        segment_hits.clear();
        x = x0 + s_exit * g;
        return 1;
      }
      x += lift * m;
    }
    active[0].tri = flat_next;
    active[0].key = -1000 - static_cast<std::int64_t>(flat_next);
  }
  for (const Obstacle& o : segment_hits) {
    Partner p;
    p.key = o.key, p.c = o.c, p.R = o.R;
    add(p, x);
  }
  return 1;
}

}  // namespace btr::mesh_walk
