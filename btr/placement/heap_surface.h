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

// The `count` drops of the scene (radius, species and order as DropSequence draws them with `seed`), each
// at a position drawn over the surface above with probability proportional to its height (positions from a
// separate generator seeded with `seed` and `draw`, so the same arguments give the same drops and another
// `draw` an independent set of positions), inside the container with one radius of clearance from its walls.
// `surface` (optional) receives the solved surface.
// Throws SceneError for a scene without a point or region source, and std::invalid_argument for an angle
// outside (0, 90) degrees or a packing fraction outside (0, 1].
std::vector<Drop> heap_surface_drops(const Scene& scene, std::uint64_t seed, std::int64_t count, double angle,
                                     double packing_fraction, HeapSurface* surface = nullptr, std::uint64_t draw = 0);

}  // namespace btr
