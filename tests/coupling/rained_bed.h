#pragma once
// A small BTR bed for the compaction tests: `count` grains of make_scene's (r 0.8-1.2 mm, Young 5e6) rained into
// a 12 mm periodic cell (400: about 9 largest diameters deep), relax.max_time 1 s.
#include <string>

#include "btr/placement/run_scene.h"
#include "coupling/io/scene_json.h"
#include "relax_fixtures.h"

namespace btr_test {

struct RainedBed {
  btr::Scene scene;
  btr::Packing packing;
};

inline RainedBed rained_bed(const std::string& name, int count) {
  RainedBed b;
  b.scene = make_scene(name, 3, container(btr::ContainerKind::Periodic, 0.012, 0.012));
  b.scene.source.kind = btr::SourceSpec::Kind::Rain;
  b.scene.grains.components[0].material.young = 5e6;
  b.scene.relax.max_time = 1.0;
  b.packing.grains = btr::run_scene(b.scene, 3, count, {}).grains;
  b.packing.meta = {{"scene", btr::scene_to_json(b.scene)}, {"dimension", 3}};
  return b;
}

}  // namespace btr_test
