#pragma once
// The sequence of grains a scene drops: radius, species and drop position of each, in order.
//
// One std::mt19937_64 seeded with `seed`; every double is (u64 >> 11) * 2^-53, in [0, 1). Per grain
// the draws come in this fixed order:
//   1. the component (only for mixtures): the first whose cumulative number fraction exceeds u;
//   2. the radius (uniform, constant-mass: one draw; constant, list: none);
//   3. the position: point in 2D one draw (segment), in 3D a disk by rejection (pairs of draws until
//      inside); rain and region one draw per axis (cylinder: a disk by rejection); list: none.
// A scene's [intruder] is the first drop (no draws), before the count bed grains.
// Only +, -, *, / and sqrt touch the draws, so the sequence is bit-identical on any IEEE machine.
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "btr/placement/deposition.h"
#include "btr/placement/mesh_index.h"
#include "btr/scene/drop_list.h"
#include "btr/scene/scene.h"

namespace btr {

// Mean of R^k (k = 1, 2, 3) for one radius distribution, exact (analytic, or the list's average).
double radius_moment(const RadiusSpec& spec, int k);

// Number fraction of each component (in the scene's component order): volume fractions are divided by
// the component's mean grain volume (disk area in 2D, sphere volume in 3D) and renormalised.
std::vector<double> number_fractions(const GrainsSpec& grains, int dimension);

class DropSequence {
 public:
  // Reads the list source's file again if there is one (throws SceneError if it went bad or has
  // fewer rows than scene.grains.count).
  DropSequence(const Scene& scene, std::uint64_t seed);

  std::int64_t count() const { return count_; }
  double r_min() const { return r_min_; }
  double r_max() const { return r_max_; }

  // The next drop; throws std::out_of_range after count() drops.
  Drop next();

 private:
  double uniform();
  double radius(std::size_t component);
  void disk(double radius, double& x, double& y);  // uniform on the disk about 0
  void position(double r, Drop& d);
  void check_mesh_footprint(const Scene& scene) const;  // SceneError: a source that cannot reach the mesh

  int dimension_;
  Container container_;
  SourceSpec source_;
  std::vector<Component> components_;
  std::vector<double> cumulative_;     // cumulative number fractions
  std::vector<std::size_t> list_pos_;  // next index of each component's radius list
  std::vector<ListedDrop> listed_;
  std::optional<IntruderSpec> intruder_;  // the first drop, when the scene has one
  std::shared_ptr<const MeshIndex> mesh_;  // a mesh container: rain lands only inside its footprint
  std::mt19937_64 rng_;
  std::int64_t count_ = 0, drawn_ = 0;
  double r_min_ = 0.0, r_max_ = 0.0;
};

}  // namespace btr
