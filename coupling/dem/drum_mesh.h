#pragma once
// The rotating drum's surface as a triangle mesh for the DEM engines (both take it as a mesh container's
// triangles: LIGGGHTS fix mesh/surface, YADE ymport.stl). Its axis is the drum's: along y through x = 0,
// z = radius (btr/model/container.h).
//  - The cylinder is n flat panels tangent to the true cylinder (vertices at R / cos(pi/n)), n the smallest
//    power of two (at least 64) whose sagitta R (1 - cos(pi/n)) is below kDrumSagittaFraction of the smallest
//    grain radius, so a panel is never more than that inside or outside the exact cylinder the checks use.
//  - 3D: the cylinder spans y in [-length/2, length/2]; with end walls, two flat discs on its rims close it
//    (rings of half as many vertices inwards: triangles of about equal sides); with periodic ends there are none.
//  - 2D: the disks lie in y = 0; the cylinder spans the thin slab y in [-r_max/2, r_max/2] (inside the
//    slab of one largest diameter the 2D coupling runs in).
#include <memory>

#include "btr/model/container.h"
#include "btr/model/grain.h"
#include "btr/model/mesh.h"

namespace btr {

inline constexpr double kDrumSagittaFraction = 1e-3;

// The panel count of a drum of radius `radius` holding grains no smaller than r_min (> 0).
int drum_panels(double radius, double r_min);

// The drum's mesh for these grains (container.kind must be Drum; grains not empty).
std::shared_ptr<const TriangleMesh> drum_mesh(const Container& container, int dimension, const Grains& grains);

}  // namespace btr
