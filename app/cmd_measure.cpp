// `btr measure PACKING.csv [-o OUT.json]`: the structural measures of a packing (the scene is read from
// PACKING.json beside it), the same numbers `btr deposit` and `btr relax` store in their JSON.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "btr/measures/metrics.h"
#include "btr/scene/scene_toml.h"
#include "commands.h"
#include "coupling/io/atomic_file.h"
#include "load_packing.h"
#include "measures_json.h"
#include "validators.h"

namespace btr_app {
namespace {

std::string per_grain_csv(const btr::Grains& grains, int dimension, const btr::PackingMeasures& m) {
  const std::vector<double> depth = btr::surface_depth(grains, dimension);
  const btr::BulkMeasures& b = m.bulk;
  std::string out = "id,coordination,in_window,surface_depth\n";
  char row[120];
  for (std::size_t i = 0; i < grains.size(); ++i) {
    const bool inside = b.valid && btr::in_bulk_window(b, grains[i].x, dimension);
    std::snprintf(row, sizeof row, "%zu,%d,%d,%.17g\n", i + 1, m.coordination[i], inside ? 1 : 0, depth[i]);
    out += row;
  }
  return out;
}

}  // namespace

Runner add_measure_command(CLI::App& app) {
  struct Options {
    std::string packing, out, per_grain, scene;
    btr::MetricsOptions metrics;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "measure",
      "Structural measures of a packing: bulk window, packing fraction, coordination and its histogram, g(r),\n"
      "heap angle (point sources), surface profile, segregation index. The scene is read from PACKING.json.\n"
      "Writes the JSON object `btr deposit` stores under \"measures\" (stdout, or -o FILE).");
  cmd->add_option("packing", o->packing, "PACKING.csv (the scene is read from PACKING.json beside it)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", o->out, "write the JSON here (default: stdout)");
  cmd->add_option("--scene", o->scene, "scene TOML to take the container and source from (default: PACKING.json's)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--margin", o->metrics.margin_diameters,
                  "bulk window margin from floor, walls and free surface, in largest diameters")
      ->capture_default_str()
      ->check(non_negative_number());
  cmd->add_option("--contact-tolerance", o->metrics.contact_tol,
                  "contact: gap < tolerance x smaller radius")
      ->capture_default_str()
      ->check(non_negative_number());
  cmd->add_option("--rdf-max", o->metrics.rdf_max_d, "g(r) range in mean diameters")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_option("--per-grain", o->per_grain,
                  "also write a CSV: id, coordination, in_window (0/1), surface_depth [m] below the free surface");

  return [o]() -> int {
    PackingWithScene p;
    try {
      if (o->scene.empty()) {
        p = load_packing_with_scene(o->packing);
      } else {
        p.packing = btr::read_packing(o->packing);
        p.scene = btr::load_scene(o->scene);
      }
    } catch (const std::exception& e) {
      std::cerr << "btr measure: " << e.what() << "\n";
      return kBadInput;
    }
    try {
      const btr::Scene& sc = p.scene;
      const btr::PackingMeasures m = measure_in_scene(p.packing.grains, sc, o->metrics);
      const std::string text = measures_to_json(m).dump(1) + "\n";
      if (o->out.empty()) std::cout << text;
      else btr::write_text_file(o->out, text);
      if (!o->per_grain.empty()) btr::write_text_file(o->per_grain, per_grain_csv(p.packing.grains, sc.dimension, m));
      return kSuccess;
    } catch (const std::exception& e) {
      std::cerr << "btr measure: " << e.what() << "\n";
      return kInternalFailure;
    }
  };
}

}  // namespace btr_app
