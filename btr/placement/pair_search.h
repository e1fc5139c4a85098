#pragma once
// All pairs of grains within a cut-off of each other in a fixed packing, periodic axes at the nearest image (the
// container's wraps_x / wraps_y). The one pair search of the measures (coordination, g(r)), of the
// overlaps handed to DEM and of the cutting of cluster deposits. The placement's NeighbourGrid
// (neighbour_grid.h) does another job: grains inserted one by one, read by column and by box, every
// periodic image apart. The self-check keeps its own search on purpose (btr/verify links no placement).
//
// Cells are cutoff / m wide, m = cells_per_cutoff or fewer, so that no cell is narrower than the largest
// grain's diameter (a periodic axis holds its period in whole cells, at least that wide); on an axis that
// does not wrap, cell k covers [k w, (k + 1) w). A cell keeps its grains in index order, and the cells a
// query reads are visited z, then y, then x, each from below: the order is a function of the positions,
// the same in every run.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "btr/model/container.h"
#include "btr/model/grain.h"

namespace btr {

class PairSearch {
 public:
  // dimension 2: disks in the x-z plane; cells_per_cutoff >= 1 (narrower cells read less needless volume
  // for a cut-off of several diameters; at most 8).
  PairSearch(const Grains& grains, int dimension, const Container& container, double cutoff,
             int cells_per_cutoff = 1);

  // f(i, j, d) once for every pair of grains i != j whose nearest-image separation d = x_j - x_i has
  // d.squaredNorm() <= cutoff^2 (which of the two is i is unspecified). A pair at the cut-off to
  // within round-off may be left out.
  template <class F>
  void for_each_pair(F&& f) const;

  // f(j, d) for every grain j != i with d = x_j - x_i (nearest image), d.squaredNorm() <= cutoff^2, in the
  // order of the cells around i and, in each cell, of the grain indices.
  template <class F>
  void for_neighbours(std::size_t i, F&& f) const;

 private:
  struct Cell {
    long x, y, z;
    std::uint32_t begin, end;  // positions [begin, end) in pos_ / index_
  };
  static constexpr int kMaxReach = 8;
  long coordinate(double v, int axis) const;
  // The distinct cells within reach_ of cell c along one axis; returns their number.
  int axis_cells(int axis, long c, long* out) const;
  // The positions of cell (x, y, z) in pos_ (empty if none).
  void range(long x, long y, long z, std::uint32_t& begin, std::uint32_t& end) const;
  Vec3 separation(const Vec3& to, const Vec3& from) const {
    Vec3 d = to - from;
    for (int a = 0; a < 2; ++a)
      if (period_[a] > 0.0) d[a] = minimum_image(d[a], period_[a]);
    return d;
  }
  template <class F>
  void visit_around(long cx, long cy, long cz, F&& g) const;

  double cut2_;
  int reach_;
  double period_[3] = {0.0, 0.0, 0.0};  // > 0 on an axis that wraps
  double width_[3] = {1.0, 1.0, 1.0};
  long lo_[3] = {0, 0, 0}, n_[3] = {1, 1, 1};  // dense: cells lo .. lo + n - 1; periodic: 0 .. n - 1
  bool dense_ = true;
  std::vector<Vec3> pos_;                 // centres in cell order (contiguous for the inner loops)
  std::vector<std::uint32_t> index_;      // grain index of each position
  std::vector<std::uint32_t> where_;      // position of each grain
  std::vector<std::uint32_t> start_;      // dense: cell id -> first position (one past the end: size + 1)
  std::vector<Cell> cells_;               // sparse (a packing spread far apart): occupied cells in cell order
};

template <class F>
void PairSearch::visit_around(long cx, long cy, long cz, F&& g) const {
  long xs[2 * kMaxReach + 1], ys[2 * kMaxReach + 1], zs[2 * kMaxReach + 1];
  const int nx = axis_cells(0, cx, xs), ny = axis_cells(1, cy, ys), nz = axis_cells(2, cz, zs);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        std::uint32_t begin, end;
        range(xs[i], ys[j], zs[k], begin, end);
        if (begin != end) g(begin, end);
      }
}

template <class F>
void PairSearch::for_neighbours(std::size_t i, F&& f) const {
  const std::uint32_t p = where_[i];
  const Vec3& x = pos_[p];
  visit_around(coordinate(x.x(), 0), coordinate(x.y(), 1), coordinate(x.z(), 2),
               [&](std::uint32_t begin, std::uint32_t end) {
                 for (std::uint32_t q = begin; q < end; ++q) {
                   if (q == p) continue;
                   const Vec3 d = separation(pos_[q], x);
                   if (d.squaredNorm() <= cut2_) f(std::size_t(index_[q]), d);
                 }
               });
}

template <class F>
void PairSearch::for_each_pair(F&& f) const {
  // Each pair is taken from the grain earlier in cell order; the cells around a cell are listed once for
  // all its grains.
  auto cell = [&](long cx, long cy, long cz, std::uint32_t begin, std::uint32_t end) {
    visit_around(cx, cy, cz, [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t p = begin; p < end; ++p) {
        const Vec3& x = pos_[p];
        for (std::uint32_t q = std::max(b, p + 1); q < e; ++q) {
          const Vec3 d = separation(pos_[q], x);
          if (d.squaredNorm() <= cut2_) f(std::size_t(index_[p]), std::size_t(index_[q]), d);
        }
      }
    });
  };
  if (dense_) {
    std::size_t id = 0;
    for (long z = 0; z < n_[2]; ++z)
      for (long y = 0; y < n_[1]; ++y)
        for (long x = 0; x < n_[0]; ++x, ++id)
          if (start_[id] != start_[id + 1]) cell(lo_[0] + x, lo_[1] + y, lo_[2] + z, start_[id], start_[id + 1]);
  } else {
    for (const Cell& c : cells_) cell(c.x, c.y, c.z, c.begin, c.end);
  }
}

}  // namespace btr
