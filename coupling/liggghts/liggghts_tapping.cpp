// The LIGGGHTS script's tapping (liggghts_tapping.h). Syntax: LIGGGHTS 3.8's fix mesh/surface, fix move/mesh
// (wiggle amplitude Ax Ay Az period P: z = A sin(2 pi t / P), t from the fix's creation) and fix wall/gran mesh.
#include "coupling/liggghts/liggghts_tapping.h"

#include <filesystem>
#include <sstream>

#include "btr/model/mesh.h"
#include "btr/model/number_text.h"
#include "coupling/io/mesh_stl.h"

namespace btr {

std::string liggghts_tap_dump(long tap) { return "btr_tap_" + std::to_string(tap) + ".dump"; }

std::string liggghts_tap_floor(double x_lo, double x_hi, double y_lo, double y_hi, int wall_type,
                               const std::string& models, const std::string& wall_fix, const std::string& dir) {
  TriangleMesh floor;
  floor.file = kLiggghtsTapFloor;
  floor.vertices = {Vec3(x_lo, y_lo, 0.0), Vec3(x_hi, y_lo, 0.0), Vec3(x_hi, y_hi, 0.0), Vec3(x_lo, y_hi, 0.0)};
  floor.triangles = {{0, 1, 2}, {0, 2, 3}};
  floor.lo = Vec3(x_lo, y_lo, 0.0);
  floor.hi = Vec3(x_hi, y_hi, 0.0);
  write_mesh_stl(floor, (std::filesystem::path(dir) / kLiggghtsTapFloor).string());
  std::ostringstream s;
  s << "# The floor: a mesh over the box's footprint, moved by fix btr_tap_move during each tap.\n"
    << "fix btr_tap_floor_mesh all mesh/surface file " << kLiggghtsTapFloor << " type " << wall_type << "\n"
    << "fix " << wall_fix << " all wall/gran " << models << " mesh n_meshes 1 meshes btr_tap_floor_mesh store_force yes\n";
  return s.str();
}

namespace {

// The script's blow-up guard after a run (as the stop rule's loop has it).
std::string blowup_guard() {
  return "if \"${btr_ekin} > ${btr_bound}\" then &\n"
         "  \"print 'BTR-FAILURE kinetic energy ${btr_ekin} J above the bound ${btr_bound} J at t = ${btr_time} s'\" "
         "quit\n";
}

}  // namespace

std::string liggghts_tap_loop(const TapSchedule& tap, const std::string& dump_columns, const std::string& dump_format) {
  std::ostringstream s;
  s << "# Tapping: " << tap.taps << " taps. Each: the floor moves by z = " << g6(tap.amplitude) << " m x sin(2 pi t / "
    << g6(tap.period) << " s) for one period\n# (" << tap.steps_per_tap << " steps; Gamma = " << g6(tap.gamma)
    << ", f = " << g6(tap.frequency) << " Hz), then rests in windows of " << tap.steps_per_check
    << " steps until the kinetic energy is below\n# btr_kinetic at the ends of two windows in a row (at most "
    << tap.max_rest_checks + 1 << " windows); then the grains are written to btr_tap_<k>.dump.\n"
    << "variable btr_step equal step\n"
    << "variable btr_tap loop " << tap.taps << "\n"
    << "label btr_tap_loop\n"
    << "fix btr_tap_move all move/mesh mesh btr_tap_floor_mesh wiggle amplitude 0 0 " << g17(tap.amplitude)
    << " period " << g17(tap.period) << "\n"
    << "run " << tap.steps_per_tap << " post no\n"
    << blowup_guard()
    << "print \"BTR-TAP-MOVED ${btr_tap} t = ${btr_time} kinetic = ${btr_ekin}\"\n"
    << "unfix btr_tap_move\n"
    << "run " << tap.steps_per_check << " post no\n"
    << blowup_guard()
    << "variable btr_previous equal ${btr_ekin}\n"
    << "variable btr_rest delete\n"
    << "variable btr_rest loop " << tap.max_rest_checks << "\n"
    << "label btr_rest_loop\n"
    << "run " << tap.steps_per_check << " pre no post no\n"
    << blowup_guard()
    << "if \"${btr_previous} < ${btr_kinetic} && ${btr_ekin} < ${btr_kinetic}\" then \"jump SELF btr_rested\"\n"
    << "variable btr_previous equal ${btr_ekin}\n"
    << "next btr_rest\n"
    << "jump SELF btr_rest_loop\n"
    << "print \"BTR-TAP-RESTED ${btr_tap} max-rest t = ${btr_time} kinetic = ${btr_ekin} step = ${btr_step}\"\n"
    << "jump SELF btr_tap_output\n"
    << "label btr_rested\n"
    << "print \"BTR-TAP-RESTED ${btr_tap} settled t = ${btr_time} kinetic = ${btr_ekin} step = ${btr_step}\"\n"
    << "label btr_tap_output\n"
    << "write_dump all custom btr_tap_${btr_tap}.dump" << dump_columns << " modify sort id format \"" << dump_format
    << "\"\n"
    << "next btr_tap\n"
    << "jump SELF btr_tap_loop\n"
    << "print \"BTR-STOP taps t = ${btr_time} s\"\n";
  return s.str();
}

}  // namespace btr
