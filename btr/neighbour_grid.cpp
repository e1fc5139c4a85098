#include "btr/neighbour_grid.h"

#include <algorithm>
#include <stdexcept>

namespace btr {

NeighbourGrid::NeighbourGrid(int dimension, const Container& c, double r_max)
    : dimension_(dimension), periodic_(c.kind == ContainerKind::Periodic), grows_(c.kind == ContainerKind::Open),
      h_(2.0 * r_max) {
  hx_ = hy_ = h_;
  auto span = [&](double length, double& origin, long& n, double& width) {
    origin = -0.5 * length;
    if (periodic_) {
      n = std::max(1L, static_cast<long>(std::floor(length / h_)));
      width = length / n;
    } else {
      n = std::max(1L, static_cast<long>(std::ceil(length / h_)));
      width = h_;
    }
  };
  switch (c.kind) {
    case ContainerKind::Open:
      x0_ = 0.0; y0_ = 0.0; ix0_ = -8; nx_ = 16;
      iy0_ = dimension == 3 ? -8 : 0; ny_ = dimension == 3 ? 16 : 1;
      break;
    case ContainerKind::Box:
    case ContainerKind::Periodic:
      span(c.size_x, x0_, nx_, hx_);
      if (dimension == 3) span(c.size_y, y0_, ny_, hy_);
      else { y0_ = 0.0; ny_ = 1; }
      period_x_ = c.size_x;
      period_y_ = dimension == 3 ? c.size_y : 0.0;
      break;
    case ContainerKind::HeleShaw:
      span(c.size_x, x0_, nx_, hx_);
      span(c.gap, y0_, ny_, hy_);
      break;
    case ContainerKind::Cylinder:
      span(2.0 * c.radius, x0_, nx_, hx_);
      span(2.0 * c.radius, y0_, ny_, hy_);
      break;
    case ContainerKind::Drum:
      span(2.0 * c.radius, x0_, nx_, hx_);
      if (dimension == 3) span(c.size_y, y0_, ny_, hy_);
      break;
  }
  if (dimension == 2) { y0_ = -0.5 * h_; iy0_ = 0; ny_ = 1; hy_ = h_; }
  columns_.resize(static_cast<std::size_t>(nx_ * ny_));
}

NeighbourGrid::Range NeighbourGrid::x_range(double lo, double hi) const {
  return {static_cast<long>(std::floor((lo - x0_) / hx_)), static_cast<long>(std::floor((hi - x0_) / hx_))};
}

NeighbourGrid::Range NeighbourGrid::y_range(double lo, double hi) const {
  if (dimension_ == 2) return {0, 0};
  return {static_cast<long>(std::floor((lo - y0_) / hy_)), static_cast<long>(std::floor((hi - y0_) / hy_))};
}

void NeighbourGrid::grow_to(long ix, long iy) {
  long new_ix0 = ix0_, new_nx = nx_, new_iy0 = iy0_, new_ny = ny_;
  while (ix < new_ix0 || ix >= new_ix0 + new_nx) { new_ix0 -= new_nx / 2; new_nx *= 2; }
  if (dimension_ == 3)
    while (iy < new_iy0 || iy >= new_iy0 + new_ny) { new_iy0 -= new_ny / 2; new_ny *= 2; }
  std::vector<std::vector<Cell>> grown(static_cast<std::size_t>(new_nx * new_ny));
  for (long y = iy0_; y < iy0_ + ny_; ++y)
    for (long x = ix0_; x < ix0_ + nx_; ++x)
      grown[(x - new_ix0) + new_nx * (y - new_iy0)] = std::move(columns_[column_of(x, y)]);
  columns_ = std::move(grown);
  ix0_ = new_ix0; nx_ = new_nx; iy0_ = new_iy0; ny_ = new_ny;
}

void NeighbourGrid::insert(std::int32_t index, const Vec3& x, double r) {
  long ix = static_cast<long>(std::floor((x.x() - x0_) / hx_));
  long iy = dimension_ == 3 ? static_cast<long>(std::floor((x.y() - y0_) / hy_)) : 0;
  if (periodic_) {
    ix -= floor_div(ix, nx_) * nx_;
    if (dimension_ == 3) iy -= floor_div(iy, ny_) * ny_;
  } else if (grows_) {
    if (ix < ix0_ || ix >= ix0_ + nx_ || iy < iy0_ || iy >= iy0_ + ny_) grow_to(ix, iy);
  } else {
    ix = std::clamp(ix, ix0_, ix0_ + nx_ - 1);  // a centre on the wall's cell edge: round-off only
    iy = std::clamp(iy, iy0_, iy0_ + ny_ - 1);
  }
  const long iz = std::max(0L, static_cast<long>(std::floor(x.z() / h_)));
  auto& column = columns_[column_of(ix, iy)];
  if (static_cast<long>(column.size()) <= iz) column.resize(iz + 1);
  column[iz].push_back(Entry{x.x(), x.y(), x.z(), r, index});
}

}  // namespace btr
