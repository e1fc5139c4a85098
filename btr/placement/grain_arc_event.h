#pragma once
// The events of a grain rolling among fixed grains along a circular arc: the grains it meets and, on two
// supports, the first lift-off. One implementation for the analytic engine's roll (btr/placement/deposition.cpp,
// which adds its walls) and the mesh placement's exact moves where no triangle can be met
// (btr/placement/mesh_exact_moves.cpp); and the first grain met along a straight segment (a slide down a face).
#include <cstdint>
#include <vector>

#include "btr/placement/circle_arc.h"
#include "btr/placement/contacts.h"
#include "btr/placement/obstacle.h"

namespace btr {

class NeighbourGrid;

// Offers to ev the grains (spheres) of `grid` met by a grain of radius r (every radius at most r_max) moving
// along `arc` from `start` (its centre now, arc.at(0) up to round-off); `supports` are never met. Grains near
// the arc's first 1.5 radii of travel are read first, the rest only up to the event found so far.
void offer_grains_on_arc(const NeighbourGrid& grid, double r, double r_max, const Contacts& supports,
                         const CircleArc& arc, const Vec3& start, Event& ev);

// With two supports (the circle where their contact surfaces meet), the first point before ev.t where one
// of them unloads: ev becomes that lift-off (ev.lift_off its index in `supports`).
void offer_lift_offs(const Contacts& supports, const CircleArc& arc, Event& ev);

// The first event along `arc` among grains alone: both of the above from arc.at(0).
Event first_grain_event(const NeighbourGrid& grid, double r, double r_max, const Contacts& supports,
                        const CircleArc& arc);

// The first grains met by a grain of radius r moving along the segment x0 + s g, s in [0, s_max] (g a
// unit vector): the smallest s and the grains met there (none: s_max). A grain touched at x0 is met
// only if the segment heads into it; `skip` (n_skip keys) are never met.
double first_grain_on_segment(const NeighbourGrid& grid, double r, double r_max, const Vec3& x0, const Vec3& g,
                              double s_max, const std::int64_t* skip, int n_skip, std::vector<Obstacle>& hits);

}  // namespace btr
