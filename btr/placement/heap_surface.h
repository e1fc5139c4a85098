#pragma once
// Drops that build a heap of a chosen flank angle (`btr settle` of a heap, docs/guide/settle.md).
//
// A BTR grain stops at its first three-point support, so a BTR heap stands far steeper than a poured one
// (57 against 20 deg on docs/open_floor_heap's scene). Raining the grains over the footprint in proportion to
// the height of the heap wanted builds that heap instead: each column receives the grains that fill it, and a
// slope below BTR's own limit keeps its shape. The surface is
//   h(p) = H - tan(angle) * (distance from p to the source's footprint),  where positive, inside the container,
// a cone about a point source on an open floor, a ramp from a source at a Hele-Shaw cell's end wall; the apex
// height H is solved so that its volume holds the grains' solid volume at `packing_fraction`.
#include <cstdint>
#include <vector>

#include "btr/placement/deposition.h"
#include "btr/scene/scene.h"

namespace btr {

struct HeapSurface {
  double angle = 0.0;             // rad, the flank angle asked for
  double packing_fraction = 0.0;  // the solid volume is divided by this to give the heap's volume
  double apex_height = 0.0;       // H [m], solved
  double volume = 0.0;            // m^3 (2D: m^2), the grains' solid volume / packing_fraction
  double reach = 0.0;             // H / tan(angle): the flank's horizontal length [m]
};

// Distance [m] in the floor plane from (x, y) to the scene's source footprint (point: a disk of radius
// `scatter` in 3D, a segment in 2D; region: its rectangle, 2D its segment); periodic containers use the
// nearest image. Throws SceneError for a rain or list source (no footprint to build a heap around).
double distance_to_source(const Scene& scene, double x, double y);

// The surface above for the `count` drops of the scene (radius, species and order as DropSequence draws them
// with `seed`), solved once; draw(k) gives the drops at positions drawn over it with probability proportional
// to its height, inside the container with one radius of clearance from its walls. Positions come from a
// generator seeded with `seed` and k: the same k gives the same drops, another k an independent set.
// The constructor throws SceneError for a scene without a point or region source, and std::invalid_argument
// for an angle outside (0, 90) degrees or a packing fraction outside (0, 1].
class HeapSurfaceSampler {
 public:
  HeapSurfaceSampler(const Scene& scene, std::uint64_t seed, std::int64_t count, double angle,
                     double packing_fraction);
  const HeapSurface& surface() const { return surface_; }
  std::vector<Drop> draw(std::uint64_t k) const;

 private:
  Scene scene_;
  std::uint64_t seed_;
  HeapSurface surface_;
  std::vector<Drop> drops_;  // radii and species in order; positions filled by draw()
  // The sampling grid: cells of side h from (x0, y0), nx per row, ny rows (2D: one), row-major; the running sum
  // of the surface's height over the cells (flat where a cell lies outside the container or beyond the foot).
  double x0_ = 0.0, y0_ = 0.0, h_ = 0.0;
  long nx_ = 1;
  std::vector<double> cumulative_;
};

}  // namespace btr
