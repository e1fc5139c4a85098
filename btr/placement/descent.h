#pragma once
// Where gravity pushes a grain held by its contacts: the projection of -z onto the cone of
// directions that do not push into any contact. Zero means the contacts carry the weight with
// non-negative normal forces.
#include <array>
#include <cstddef>

#include "btr/model/grain.h"

namespace btr {

// The most contacts a grain may hold at once (a large grain among small ones can meet many in one
// event); the placement reports a grain that would need more as a PlacementError.
constexpr int kMaxContacts = 16;

struct Descent {
  Vec3 direction = Vec3::Zero();  // unnormalised; zero when the weight is carried
  // loaded[i] is true for the contacts that carry load (positive multiplier) and stay active.
  std::array<bool, kMaxContacts> loaded{};
};

// normals[i] is the unit normal of contact i; at most kMaxContacts contacts (more: std::length_error).
Descent descend(const Vec3* normals, std::size_t count);

// Two supports with unit normals a and b carry the part g of gravity normal to the path: is the load of
// support a negative (it lifts off)? The load is ((g x b) . (a x b)) / |a x b|^2; its sign is read off
// the numerator, which has no division to give NaN when a and b are nearly parallel. Exactly
// parallel normals (|a x b| = 0: the load is undetermined) give false.
inline bool unloads(const Vec3& g, const Vec3& a, const Vec3& b) { return g.cross(b).dot(a.cross(b)) < 0.0; }

}  // namespace btr
