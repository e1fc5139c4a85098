#pragma once
// The state of one grain being placed in a mesh container and the moves that change it, shared by the
// stepped walker (btr/placement/mesh_placement.cpp) and the exact moves away from the triangles
// (btr/placement/mesh_exact_moves.cpp). Internal to those two files.
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "btr/placement/deposition.h"
#include "btr/placement/descent.h"
#include "btr/placement/grain_arc_event.h"
#include "btr/placement/mesh_index.h"
#include "btr/placement/mesh_placement.h"
#include "btr/placement/neighbour_grid.h"
#include "btr/placement/obstacle.h"

namespace btr::mesh_walk {

// A contact partner: a fixed grain (one periodic image) or a triangle.
struct Partner {
  std::int64_t key = 0;  // sphere_key for grains, -1000 - t for triangle t
  int tri = -1;
  Vec3 c = Vec3::Zero();  // grain: centre
  double R = 0.0;         // grain: contact distance r + r_j
};

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
  std::vector<Obstacle> segment_hits;  // reused: the grains a slide meets first

  // The lists' storage, handed from one walker to the next (cleared).
  struct Lists {
    std::vector<Partner> active, near, entering, scratch;
    std::vector<int> tris, face_hits;
    std::vector<Obstacle> segment_hits;
  };
  void take(Lists& l) {
    active.swap(l.active), near.swap(l.near), entering.swap(l.entering), scratch.swap(l.scratch);
    tris.swap(l.tris), face_hits.swap(l.face_hits), segment_hits.swap(l.segment_hits);
    active.clear(), near.clear(), entering.clear(), scratch.clear(), tris.clear(), face_hits.clear(), segment_hits.clear();
  }
  void give(Lists& l) {
    active.swap(l.active), near.swap(l.near), entering.swap(l.entering), scratch.swap(l.scratch);
    tris.swap(l.tris), face_hits.swap(l.face_hits), segment_hits.swap(l.segment_hits);
  }

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
  bool face_contact(int t, const Vec3& x, Vec3& n, double& margin, double tol) const;
  bool roll_off_top(const Vec3& x, Vec3& d, std::uint64_t salt) const;
  double path_curvature(const Vec3& x, const Vec3& xb, double travel) const;
  double step_graze(const Vec3& x, const Vec3& xb, double h, const Vec3& d, double sb) const;
  Vec3 place(Vec3 x);
};

}  // namespace btr::mesh_walk
