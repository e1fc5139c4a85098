#pragma once
// Where a vertical line comes within a distance of a triangle, in closed form: the set of points within
// distance d of triangle abc is the union of the slab over its face, a cylinder about each edge and a
// sphere about each vertex, each convex, so the line meets each in an interval (linear and quadratic
// conditions in the height) and the union in one interval.
#include "btr/model/grain.h"

namespace btr {

struct HeightInterval {
  double lo = 1.0, hi = -1.0;  // empty while lo > hi
  bool empty() const { return lo > hi; }
};

// The offsets s (the heights x.z + s) at which the vertical line through x is within d of triangle abc
// (unit normal n).
HeightInterval line_within(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n, const Vec3& x, double d);

}  // namespace btr
