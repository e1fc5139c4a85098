// The YADE engine adapter: writes the packing and the batch script, says how to run it, reads the result.
//
// YADE is run by importing its Python module into Debian's /usr/bin/python3
// (PYTHONPATH=/usr/lib/x86_64-linux-gnu/yade-double/py), not through the `yade` launcher: the launcher
// opens a TCP Python console (port 9000+) and an XML-RPC server (port 21000+, every interface) at each
// start, and a run started by btr must not expose a Python console to the network. The script still runs
// unchanged with `yade -n -x relax_yade.py` for users who prefer the launcher (e.g. on a cluster).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "btr/verify/cluster_unwrap.h"
#include "coupling/io/atomic_file.h"
#include "coupling/dem/drum_mesh.h"
#include "coupling/io/mesh_stl.h"
#include "coupling/yade/yade_script.h"

namespace btr {
namespace {

namespace fs = std::filesystem;

// The packing for the script: id,x,y,z,radius,species, and a cluster column (0 = a free grain) when the
// packing has rigid clusters, which the script makes clumps. A clump needs its members together: in a
// periodic cell they are written at their unwrapped positions (btr/verify/cluster_unwrap.h), which may lie outside
// the cell; the script wraps the relaxed positions into the cell again.
std::string packing_csv(const Packing& packing, const Scene& scene) {
  const bool clusters = std::any_of(packing.grains.begin(), packing.grains.end(), [](const Grain& g) { return g.cluster != 0; });
  const std::vector<Vec3> x = unwrap_clusters(packing.grains, scene.dimension, scene.container);
  std::string out = clusters ? "id,x,y,z,radius,species,cluster\n" : "id,x,y,z,radius,species\n";
  char line[288];
  for (std::size_t i = 0; i < packing.grains.size(); ++i) {
    const Grain& g = packing.grains[i];
    int n = std::snprintf(line, sizeof line, "%zu,%.17g,%.17g,%.17g,%.17g,%d", i + 1, x[i].x(), x[i].y(), x[i].z(), g.r,
                          g.species);
    if (clusters) n += std::snprintf(line + n, sizeof line - n, ",%d", static_cast<int>(g.cluster));
    out.append(line, static_cast<std::size_t>(n));
    out += '\n';
  }
  return out;
}

class YadeAdapter : public EngineAdapter {
 public:
  std::vector<std::string> write_inputs(const Packing& packing, const Scene& scene, const RelaxSettings& settings,
                                        const RelaxPlan& plan, const std::string& dir) const override {
    if (settings.np < 1) throw std::invalid_argument("relax: np (YADE threads) must be >= 1, got " + std::to_string(settings.np));
    const std::string script = yade_script(packing, scene, plan);  // validates before anything is written
    const fs::path d(dir);
    // Outputs of an earlier run in the same folder must not be read as this run's.
    for (const char* name : {yade_files::kStatus, yade_files::kFinal, yade_files::kKinetic, yade_files::kContacts,
                             yade_files::kTaps})
      fs::remove(d / name);
    write_text_file((d / yade_files::kPacking).string(), packing_csv(packing, scene));
    write_text_file((d / yade_files::kScript).string(), script);
    fs::permissions(d / yade_files::kScript, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                    fs::perm_options::add);
    std::vector<std::string> written{(d / yade_files::kScript).string(), (d / yade_files::kPacking).string()};
    if (scene.container.kind == ContainerKind::Mesh || scene.container.kind == ContainerKind::Drum) {
      write_mesh_stl(scene.container.kind == ContainerKind::Mesh ? *scene.container.mesh
                                                                 : *drum_mesh(scene.container, scene.dimension, packing.grains),
                     (d / yade_files::kMesh).string());
      written.push_back((d / yade_files::kMesh).string());
    }
    return written;
  }

  EngineCommand command(const std::string& dir, const RelaxSettings& settings) const override {
    EngineCommand cmd;
    cmd.argv = {"/usr/bin/python3", (fs::absolute(dir) / yade_files::kScript).string()};
    cmd.env["PYTHONPATH"] = kYadePythonPath;
    cmd.env["OMP_NUM_THREADS"] = std::to_string(settings.np);  // YADE's thread count (O.numThreads)
    return cmd;
  }

  std::string log_file(const std::string& dir) const override { return (fs::path(dir) / yade_files::kLog).string(); }

  RelaxResult read_back(const std::string& dir, const Packing& original, const Scene& scene,
                        const RelaxPlan& plan) const override {
    return yade_read_back(dir, original, scene, plan);
  }

  // The script exits with status 1 after writing a "failed" status with its failure_kind.
  Grains read_snapshot(const std::string& dir, std::size_t k, const Packing& original) const override {
    return yade_read_snapshot(dir, k, original);
  }

  std::vector<TapSnapshot> read_taps(const std::string& dir, const Packing& original,
                                     const RelaxPlan& plan) const override {
    return yade_read_taps(dir, original, plan);
  }

  std::optional<EngineFailure> failure_after_exit(const std::string& dir, const Packing& original, const Scene& scene,
                                                  const RelaxPlan&) const override {
    return yade_failure_after_exit(dir, original, scene);
  }
};

}  // namespace

std::unique_ptr<EngineAdapter> make_yade_adapter() { return std::make_unique<YadeAdapter>(); }

}  // namespace btr
