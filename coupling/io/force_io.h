#pragma once
// Writing a static force network (btr/measures/force_network.h) beside its packing:
//   NAME.forces.csv  header i,j,fx,fy,fz: the force on grain i from partner j (j > 0 a grain, 0 the
//                    floor, < 0 a wall: -1, -2, ... in dem_walls order after the floor), every
//                    contact once, %.17g;
//   NAME.forces.vtp  the force chains for ParaView: one line per contact from the centre of i to the
//                    centre of j (its periodic image) or to the contact point on the floor/wall, with
//                    cell data "force" (|f| [N]), "i" and "j".
// Both go to temporary names first and are renamed only when both were written.
#include <string>

#include "btr/measures/force_network.h"
#include "btr/model/grain.h"

namespace btr {

void write_forces(const std::string& dir, const std::string& name, const Grains& grains, const ForceNetwork& net);

}  // namespace btr
