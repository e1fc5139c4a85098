#pragma once
// The container as obstacles for a grain of radius r: the floor, flat walls and the cylinder.
#include <string>
#include <vector>

#include "btr/model/container.h"
#include "btr/placement/obstacle.h"

namespace btr {

// Floor first, then the side walls of the container (periodic and open containers have none).
// Fills `walls` (cleared first), so the placement loop can reuse one buffer for every grain.
void container_walls(const Container& container, int dimension, double r, std::vector<Obstacle>& walls);

// Empty when a grain of radius r dropped at (x, y) fits the container's footprint, else why not.
// A drop fits within 1e-12 r beyond a wall (round-off of the caller's arithmetic).
std::string drop_misfit(const Container& container, int dimension, double x, double y, double r);

// A drop that fits (drop_misfit) but lies within that round-off beyond a wall is moved onto the wall, so
// the grain cannot fall past it.
void onto_footprint(const Container& container, int dimension, double& x, double& y, double r);

}  // namespace btr
