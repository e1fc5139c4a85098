#pragma once
// A contact partner of the grain being placed, written as the surface its centre must not cross:
//   sphere    a fixed grain (one periodic image of it): |x - c| = R with R = r + r_j
//   plane     the floor or a flat wall: n.x = offset (n points into the container)
//   cylinder  the inside of a vertical cylinder about the z axis: |x_h| = R with R = R_c - r
//   drum      the inside of a horizontal cylinder with its axis along y through c = (0, 0, z_axis):
//             |(x - c) without y| = R with R = R_drum - r
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "btr/model/grain.h"

namespace btr {

// The identity of one periodic image of fixed grain `index` (image: NeighbourGrid::image_code, below 2^30),
// distinct for every grain and image, and non-negative (walls have negative keys).
inline std::int64_t sphere_key(std::int32_t index, int image) {
  return (static_cast<std::int64_t>(index) << 30) | static_cast<std::int64_t>(image);
}

struct Obstacle {
  enum class Kind : std::uint8_t { Sphere, Plane, Cylinder, Drum };
  Kind kind = Kind::Sphere;
  std::int64_t key = 0;  // identity: sphere_key(grain index, image code) for spheres, -1 - wall number for walls
  Vec3 c = Vec3::Zero(); // sphere: centre (shifted to the image); plane: unit normal; drum: a point of the axis
  double R = 0.0;        // sphere: contact distance; plane: offset; cylinder: radius of the centre's surface

  bool is_floor() const { return kind == Kind::Plane && c.z() > 0.5; }

  // Unit normal of the constraint at x, pointing from the partner towards the grain.
  Vec3 normal(const Vec3& x) const {
    switch (kind) {
      case Kind::Sphere: return (x - c).normalized();
      case Kind::Plane: return c;
      case Kind::Cylinder: {
        Vec3 h(-x.x(), -x.y(), 0.0);
        return h.normalized();
      }
      case Kind::Drum: return Vec3(-x.x(), 0.0, c.z() - x.z()).normalized();
    }
    return Vec3::UnitZ();
  }

  // Signed distance-like gap: > 0 free, 0 touching, < 0 overlapping.
  double gap(const Vec3& x) const {
    switch (kind) {
      case Kind::Sphere: return (x - c).norm() - R;
      case Kind::Plane: return c.dot(x) - R;
      case Kind::Cylinder: return R - std::hypot(x.x(), x.y());
      case Kind::Drum: {
        const double dz = x.z() - c.z();
        return R - std::sqrt(x.x() * x.x() + dz * dz);  // no overflow to guard against: sqrt beats hypot
      }
    }
    return 0.0;
  }
};

// The circle along which a grain rolls on two supports: where its contact sphere about sphere p meets q's
// contact sphere (q a sphere) or q's offset plane n.x = R (q a plane). rho is 0 where they only touch.
struct SupportCircle {
  Vec3 C, axis;  // centre, unit normal of its plane
  double rho;
};
inline SupportCircle support_circle(const Obstacle& p, const Obstacle& q) {
  SupportCircle k;
  double s;
  if (q.kind == Obstacle::Kind::Sphere) {
    const double D = (q.c - p.c).norm();
    k.axis = (q.c - p.c) / D;
    s = (p.R * p.R - q.R * q.R + D * D) / (2.0 * D);
  } else {
    k.axis = q.c;
    s = q.R - q.c.dot(p.c);
  }
  k.C = p.c + s * k.axis;
  k.rho = std::sqrt(std::max(0.0, p.R * p.R - s * s));
  return k;
}

}  // namespace btr
