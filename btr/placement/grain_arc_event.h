#pragma once
// The first event of a grain moving among fixed grains along a circular arc (the exact roll of the
// analytic engine, btr/placement/deposition.cpp, without its walls) or a straight segment (a slide down a
// face), for the mesh placement's exact moves where no triangle can be met (btr/placement/mesh_placement.cpp).
#include <cstdint>
#include <vector>

#include "btr/placement/circle_arc.h"
#include "btr/placement/obstacle.h"

namespace btr {

class NeighbourGrid;

struct ArcEvent {
  double t = 0.0;             // where along the arc: arc.t_end when nothing happens before it
  int lift_off = -1;          // index in `supports` of a support that unloads at t
  std::vector<Obstacle> hits;  // the grains met at t (none for a lift-off or the arc's end)
};

// Grains (spheres) of `grid` met by a grain of radius r (every radius at most r_max) moving along
// `arc` from arc.at(0), and, with two supports, the first lift-off of one of them (the load of each
// along the circle where their contact surfaces meet). `supports`: one or two spheres, or a sphere and
// a plane; they are never met.
void first_grain_event(const NeighbourGrid& grid, double r, double r_max, const Obstacle* supports, int n_supports,
                       const CircleArc& arc, ArcEvent& ev);


// The first grains met by a grain of radius r moving along the segment x0 + s g, s in [0, s_max] (g a
// unit vector): the smallest s and the grains met there (none: s_max). A grain touched at x0 is met
// only if the segment heads into it; `skip` (n_skip keys) are never met.
double first_grain_on_segment(const NeighbourGrid& grid, double r, double r_max, const Vec3& x0, const Vec3& g,
                              double s_max, const std::int64_t* skip, int n_skip, std::vector<Obstacle>& hits);

}  // namespace btr
