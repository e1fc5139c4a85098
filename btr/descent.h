#pragma once
// Where gravity pushes a grain held by its contacts: the projection of -z onto the cone of
// directions that do not push into any contact. Zero means the contacts carry the weight with
// non-negative normal forces.
#include <array>
#include <cstddef>

#include "btr/grain.h"

namespace btr {

struct Descent {
  Vec3 direction = Vec3::Zero();  // unnormalised; zero when the weight is carried
  // loaded[i] is true for the contacts that carry load (positive multiplier) and stay active.
  std::array<bool, 8> loaded{};
  std::array<double, 8> force{};  // normal force of each contact, in units of the weight
};

// normals[i] is the unit normal of contact i; at most 8 contacts.
Descent descend(const Vec3* normals, std::size_t count);

}  // namespace btr
