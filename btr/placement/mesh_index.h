#pragma once
// The triangles of a mesh container for the placement: a grid of columns holding each triangle where its
// shadow on the x-y plane falls (the mesh never moves, so it is indexed once, apart from the grains'
// NeighbourGrid), the closest point of a triangle, a lower bound of the distance to the mesh, and the
// mesh's footprint: where a grain dropped from above lands inside.
#include <limits>
#include <string>
#include <vector>

#include "btr/model/mesh.h"

namespace btr {

class MeshIndex {
 public:
  // `cell`: the nominal column width (the neighbour grid's, two largest radii).
  MeshIndex(const TriangleMesh& mesh, double cell);

  const TriangleMesh& mesh() const { return mesh_; }
  int size() const { return static_cast<int>(mesh_.triangles.size()); }

  // How far a vertex may lie from where the CAD file meant it: half an ulp of a float32 file coordinate
  // (STL stores single precision, and VTK's reader keeps it), scaled. The two triangles of a flat panel are
  // coplanar only to about this.
  double vertex_roundoff() const { return vertex_roundoff_; }

  // Triangle t's unit normal, (b - a) x (c - a) normalized (NaN components for a degenerate triangle).
  const Vec3& normal(int t) const { return normal_[static_cast<std::size_t>(t)]; }

  // The point of triangle t closest to x.
  Vec3 closest(int t, const Vec3& x) const;
  double distance(int t, const Vec3& x) const { return (x - closest(t, x)).norm(); }
  // A cheap lower bound of distance(t, x): the larger of the distances from t's plane and from its bounding box.
  double distance_bound(int t, const Vec3& x) const;

  // Every triangle whose bounding box meets the box [lo, hi] and whose shadow meets a column under it (so
  // every triangle with a point in the box), once each, in increasing index (appended).
  void collect(const Vec3& lo, const Vec3& hi, std::vector<int>& out) const;

  // The highest centre height z <= x.z at which a sphere of radius r on the vertical line through x
  // touches triangle t while moving down into it; NaN when it does not (passes beside it, or moves away),
  // and may be NaN when that height is below z_floor (the triangle's plane puts it there).
  double fall_contact(int t, const Vec3& x, double r, double z_floor = -std::numeric_limits<double>::infinity()) const;

  // A lower bound of the distance from x to the mesh (0 near it, at most a few cells far from it): the
  // distance from the centre of x's cell, computed once per cell, less the distance of x from that centre.
  double clearance(const Vec3& x) const;

  // How many triangles the vertical line through (x, y) crosses below height z (odd: inside a cup).
  int crossings_below(double x, double y, double z) const;

  // Empty when a grain of radius r dropped at (x, y) from above the mesh falls into it: the vertical line
  // crosses the mesh an odd number of times, and no open rim (an edge of one triangle only) lies within r
  // of it horizontally. Otherwise why not, naming the file.
  std::string footprint_misfit(double x, double y, double r) const;
  // The same test without the reason (the rain draws until it holds).
  bool in_footprint(double x, double y, double r) const;

 private:
  const std::vector<int>& column(double x, double y) const;
  int rim_within(double x, double y, double r) const;
  double touching_fall(int t, const Vec3& x, double r, double lo) const;
  long ix(double x) const;
  long iy(double y) const;

  const TriangleMesh& mesh_;
  double vertex_roundoff_ = 0.0;
  std::vector<Vec3> box_lo_, box_hi_;  // each triangle's bounding box
  std::vector<Vec3> normal_;
  std::vector<std::array<int, 2>> rim_;  // edges of one triangle only (an open mesh's rims and outlets)
  std::vector<std::vector<int>> rim_columns_;  // per column, the rim edges whose x-y box meets it
  double x0_, y0_, w_;
  long nx_, ny_;
  std::vector<std::vector<int>> columns_;
  mutable std::vector<unsigned> stamp_;  // collect(): a triangle already taken in this call
  mutable unsigned visit_ = 0;
  // clearance(): cells of width fw_ over the mesh's box, each the distance of its centre from the mesh up
  // to cap_ (rounded down), NaN until asked for; empty when there would be too many cells.
  double fw_ = 0.0;
  long fnx_ = 0, fny_ = 0, fnz_ = 0;
  double cap_ = 0.0;
  mutable std::vector<float> field_;
};

}  // namespace btr
