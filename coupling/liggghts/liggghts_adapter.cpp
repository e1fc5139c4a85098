// The LIGGGHTS engine: inputs from liggghts_script.cpp, result from liggghts_readback.cpp.
#include <unistd.h>

#include <filesystem>

#include "coupling/dem/engine_adapter.h"
#include "coupling/dem/relax_plan.h"
#include "coupling/liggghts/liggghts_readback.h"
#include "coupling/liggghts/liggghts_script.h"
#include "coupling/liggghts/liggghts_tapping.h"

namespace btr {

namespace {

class LiggghtsAdapter : public EngineAdapter {
 public:
  std::vector<std::string> write_inputs(const Packing& packing, const Scene& scene, const RelaxSettings&,
                                        const RelaxPlan& plan, const std::string& dir) const override {
    // LIGGGHTS 3.8 aborts at run time on "0.05 < coefficientRestitution <= 1 required": refuse now.
    for (const Component& c : scene.grains.components)
      if (!(c.material.restitution > 0.05))
        throw RelaxRefused("species " + std::to_string(c.species) + ": restitution " +
                           std::to_string(c.material.restitution) +
                           " is outside LIGGGHTS' accepted range (0.05, 1]; use YADE or a larger restitution");
    return write_liggghts_inputs(packing, scene, plan, dir);
  }

  EngineCommand command(const std::string& dir, const RelaxSettings& settings) const override {
    EngineCommand c;
    if (settings.np > 1) {
      // No binding of ranks to cores and yielding while waiting: on a machine whose cores are shared, a
      // rank pinned to a busy core stalls every step's synchronisation while its partner spins; measured
      // on 2 loaded cores (30 000 grains, 1000 steps): 57 s pinned and spinning, 34 s without (1 rank: 32 s).
      c.argv = {"mpirun", "-np", std::to_string(settings.np), "--bind-to", "none", "--mca", "mpi_yield_when_idle", "1"};
      if (::geteuid() == 0) {  // OpenMPI refuses to run as root without both of these
        c.env["OMPI_ALLOW_RUN_AS_ROOT"] = "1";
        c.env["OMPI_ALLOW_RUN_AS_ROOT_CONFIRM"] = "1";
      }
    }
    // LIGGGHTS 3.8's STL reader (fix mesh/surface) prints to the screen without checking that there is
    // one: with "-screen none" it crashes. A mesh container's run (its inputs hold the mesh) gets a screen
    // file instead.
    const bool mesh = std::filesystem::exists(std::filesystem::path(dir) / kLiggghtsMesh) ||
                      std::filesystem::exists(std::filesystem::path(dir) / kLiggghtsTapFloor);
    for (const char* a : {"liggghts", "-in", kLiggghtsScript, "-log", kLiggghtsLog, "-screen", mesh ? kLiggghtsScreen : "none",
                          "-echo", "none"})
      c.argv.push_back(a);
    return c;
  }

  std::string log_file(const std::string& dir) const override {
    return (std::filesystem::path(dir) / kLiggghtsLog).string();
  }

  RelaxResult read_back(const std::string& dir, const Packing& original, const Scene& scene,
                        const RelaxPlan& plan) const override {
    return read_liggghts_result(dir, original, scene, plan);
  }

  Grains read_snapshot(const std::string& dir, std::size_t k, const Packing& original) const override {
    return read_liggghts_snapshot(dir, k, original);
  }

  // LIGGGHTS ends with a non-zero status on its own errors (e.g. "ERROR: Lost atoms"): the log's first
  // failure line says which.
  std::optional<EngineFailure> failure_after_exit(const std::string& dir, const Packing&, const Scene&,
                                                  const RelaxPlan&) const override {
    const std::string path = log_file(dir);
    const LiggghtsLog log = parse_liggghts_log(path);
    if (log.failure.empty()) return std::nullopt;
    return EngineFailure(log.failure_kind, path + ": " + log.failure, log.failure_values);
  }

  std::vector<TapSnapshot> read_taps(const std::string& dir, const Packing& original,
                                     const RelaxPlan& plan) const override {
    return read_liggghts_taps(dir, original, plan);
  }
};

}  // namespace

std::unique_ptr<EngineAdapter> make_liggghts_adapter() { return std::make_unique<LiggghtsAdapter>(); }

}  // namespace btr
