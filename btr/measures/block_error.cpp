#include "btr/measures/block_error.h"

#include <cmath>

namespace btr {

BlockError bulk_phi_block_error(const Grains& grains, int dimension, const Container& container,
                                const BulkMeasures& bulk) {
  BlockError e;
  if (container.kind != ContainerKind::Periodic || !bulk.valid || !bulk.slab) {
    e.note = "blocks are defined for a periodic bed's slab window only";
    return e;
  }
  const bool three = dimension == 3;
  const int nx = three ? 2 : 4, ny = three ? 2 : 1, nz = 2;
  const Box& w = bulk.window;
  const double lx = container.size_x, ly = three ? container.size_y : 0.0;
  const double dx = lx / nx, dy = ly / ny, dz = (w.hi.z() - w.lo.z()) / nz;
  std::vector<Box> blocks;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) {
        Box b;
        b.lo = Vec3(w.lo.x() + i * dx, w.lo.y() + j * dy, w.lo.z() + k * dz);
        b.hi = Vec3(w.lo.x() + (i + 1) * dx, w.lo.y() + (j + 1) * dy, w.lo.z() + (k + 1) * dz);
        blocks.push_back(b);
      }
  std::vector<double> solid(blocks.size(), 0.0);
  const int images_y = three ? 1 : 0;
  for (const Grain& g : grains) {
    if (g.x.z() + g.r <= w.lo.z() || g.x.z() - g.r >= w.hi.z()) continue;
    for (int ix = -1; ix <= 1; ++ix)
      for (int iy = -images_y; iy <= images_y; ++iy) {
        Grain image = g;
        image.x.x() += ix * lx;
        image.x.y() += iy * ly;
        for (std::size_t b = 0; b < blocks.size(); ++b) solid[b] += grain_volume_in_box(image, dimension, blocks[b]);
      }
  }
  const double block_volume = dx * dz * (three ? dy : 1.0);
  double mean = 0.0;
  for (double s : solid) {
    e.block_phi.push_back(s / block_volume);
    mean += e.block_phi.back();
  }
  const double n = static_cast<double>(blocks.size());
  mean /= n;
  double squares = 0.0;
  for (double p : e.block_phi) squares += (p - mean) * (p - mean);
  e.standard_error = std::sqrt(squares / (n - 1.0)) / std::sqrt(n);
  e.valid = true;
  e.note = three ? "the bulk window in 2 x 2 columns x 2 layers" : "the bulk window in 4 columns x 2 layers";
  return e;
}

}  // namespace btr
