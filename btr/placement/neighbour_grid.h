#pragma once
// Uniform grid over x-y columns and height, with cells at least one largest diameter wide, so the
// grains near a point are found in a constant number of cells whatever the number already placed.
// Periodic axes (a periodic container, a drum's periodic ends) wrap columns and report each grain with the shift of the image found.
// An open floor has no footprint: the grid grows as the heap spreads.
#include <cmath>
#include <cstdint>
#include <memory>
#include <type_traits>
#include <vector>

#include "btr/model/container.h"
#include "btr/model/grain.h"

namespace btr {

// Large blocks (kLargePageBytes or more) mapped on their own and offered to the kernel for 2 MiB transparent huge
// pages (madvise MADV_HUGEPAGE on Linux): a bed of 10^7 grains reads its grid at random columns, and with 4 KiB
// pages nearly every read misses the TLB. Smaller blocks come from operator new. No effect on any result.
constexpr std::size_t kLargePageBytes = std::size_t(4) << 20;
void* allocate_large_pages(std::size_t bytes);
void free_large_pages(void* p, std::size_t bytes) noexcept;
// Offers the whole 2 MiB pages inside [p, p + bytes) for huge pages (a hint; blocks under kLargePageBytes are left).
void advise_large_pages(void* p, std::size_t bytes) noexcept;

template <class T>
struct LargePageAllocator {
  using value_type = T;
  LargePageAllocator() = default;
  template <class U>
  LargePageAllocator(const LargePageAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) { return static_cast<T*>(allocate_large_pages(n * sizeof(T))); }
  void deallocate(T* p, std::size_t n) noexcept { free_large_pages(p, n * sizeof(T)); }
  friend bool operator==(const LargePageAllocator&, const LargePageAllocator&) { return true; }
  friend bool operator!=(const LargePageAllocator&, const LargePageAllocator&) { return false; }
};

// The grid's column storage: blocks bumped from large chunks (in 2 MiB pages, allocate_large_pages), a block
// freed kept on a list of its exact size for the next block of that size. Blocks over kMaxBlock bytes come
// from operator new.
class GridArena {
 public:
  GridArena() = default;
  GridArena(const GridArena&) = delete;
  GridArena& operator=(const GridArena&) = delete;
  ~GridArena();
  void* allocate(std::size_t bytes);
  void deallocate(void* p, std::size_t bytes) noexcept;

 private:
  static constexpr std::size_t kMaxBlock = std::size_t(64) << 10;
  struct Chunk { void* base; std::size_t bytes; };
  std::vector<Chunk> chunks_;
  char* next_ = nullptr;
  char* end_ = nullptr;
  std::vector<void*> free_;  // free_[bytes / 8]: free blocks of that size, linked through their first word
};

template <class T>
struct ArenaAllocator {
  using value_type = T;
  using propagate_on_container_move_assignment = std::true_type;
  using propagate_on_container_swap = std::true_type;
  GridArena* arena;
  explicit ArenaAllocator(GridArena* a) noexcept : arena(a) {}
  template <class U>
  ArenaAllocator(const ArenaAllocator<U>& o) noexcept : arena(o.arena) {}
  T* allocate(std::size_t n) { return static_cast<T*>(arena->allocate(n * sizeof(T))); }
  void deallocate(T* p, std::size_t n) noexcept { arena->deallocate(p, n * sizeof(T)); }
  friend bool operator==(const ArenaAllocator& a, const ArenaAllocator& b) { return a.arena == b.arena; }
  friend bool operator!=(const ArenaAllocator& a, const ArenaAllocator& b) { return a.arena != b.arena; }
};

class NeighbourGrid {
 public:
  NeighbourGrid(int dimension, const Container& container, double r_max);

  // Throws std::out_of_range for a non-finite centre or one outside a bounded container's grid (an
  // escaped grain; a centre on the grid's edge up to round-off is kept in the edge column), and
  // std::length_error when an open floor's grid would grow beyond its column budget.
  void insert(std::int32_t index, const Vec3& x, double r);

  // Image shifts up to this many periods are told apart by image codes.
  static constexpr long kMaxImageShift = 16384;
  static int image_code(long kx, long ky) {
    return static_cast<int>(((kx + kMaxImageShift) << 15) | (ky + kMaxImageShift));
  }
  // A hint (no effect on any result): the columns meeting [x -+ reach] x [y -+ reach] will be read from
  // height z down (z = +inf: from their top). Stage 0 asks for the columns' headers, stage 1 for their
  // layer tables, stage 2 for the entries of the two layers at z; a caller issues the stages for a
  // drop two, one and zero steps ahead, so each stage finds the memory the one before asked for.
  void prefetch(double x, double y, double reach, double z, int stage) const;

  // A hint that about n grains will be inserted in all: a fixed footprint's columns get room for 5/4 of their
  // mean share at once, so that few of them grow (and leave their old blocks behind). No effect on any result.
  void reserve(std::int64_t n);

  // Columns held (an open floor grows them as the heap spreads).
  std::size_t column_count() const { return columns_.size(); }

  double cell() const { return h_; }

  // f(index, centre, radius, image) for every grain in the cells meeting [lo, hi]; the centre is
  // that of the periodic image found, and image a code telling images of one grain apart: distinct
  // for every image shift (kx, ky) with |kx|, |ky| < kMaxImageShift (image_code; queries wider than
  // that are refused with std::length_error).
  template <class F>
  void visit_box(const Vec3& lo, const Vec3& hi, F&& f) const;

  // Visits the cells of the columns meeting [x -+ reach] x [y -+ reach], layer by layer from the
  // highest occupied layer down; before each layer calls keep_going(top of layer) and stops on false.
  template <class F, class G>
  void visit_column_down(double x, double y, double reach, double z_start, G&& keep_going, F&& f) const;

 private:
  struct Range { long lo, hi; };
  Range x_range(double lo, double hi) const;
  Range y_range(double lo, double hi) const;
  // column_of(ix, iy) = row_start(iy) + ix: a row's part worked out once where a loop walks along the row.
  long row_start(long iy) const { return nx_ * (iy - iy0_) - ix0_; }
  long column_of(long ix, long iy) const { return row_start(iy) + ix; }
  void grow_to(long ix, long iy);
  static long floor_div(long a, long b) {
    if (a >= 0 && a < b) return 0;  // inside the period: no division (the usual case)
    return a >= 0 ? a / b : -((-a + b - 1) / b);
  }

  template <class F>
  void visit_cell_range(Range rx, Range ry, long iz_lo, long iz_hi, F&& f) const;

  int dimension_;
  bool wrap_x_, wrap_y_;  // periodic axes (wraps_x, wraps_y of the container)
  bool grows_;       // open floor: the footprint is unknown in advance
  double h_;         // cell height and nominal width
  double hx_, hy_;   // cell widths (periodic: the period divided into whole cells)
  double x0_, y0_;   // coordinate of column index 0
  double period_x_ = 0.0, period_y_ = 0.0;
  long ix0_ = 0, iy0_ = 0;  // index range held: [ix0, ix0 + nx)
  long nx_ = 1, ny_ = 1;
  // A cell keeps copies of its grains' centres and radii, so a query reads memory in order.
  struct Entry {
    double x, y, z, r;
    std::int32_t index;
  };
  // The cells of one column stored contiguously, layer after layer, each in insertion order: a query
  // over a run of layers reads one block of memory instead of one heap block per cell.
  struct Column {
    explicit Column(GridArena* a) : start(ArenaAllocator<std::uint32_t>(a)), entries(ArenaAllocator<Entry>(a)) {}
    std::vector<std::uint32_t, ArenaAllocator<std::uint32_t>> start;  // layer iz holds entries [start[iz], start[iz + 1]); empty: no layer
    std::vector<Entry, ArenaAllocator<Entry>> entries;
    long layers() const { return start.empty() ? 0 : static_cast<long>(start.size()) - 1; }
  };
  std::unique_ptr<GridArena> arena_ = std::make_unique<GridArena>();  // before columns_: outlives them
  std::vector<Column, LargePageAllocator<Column>> columns_;
};

template <class F>
void NeighbourGrid::visit_cell_range(Range rx, Range ry, long iz_lo, long iz_hi, F&& f) const {
  // First gather the runs of entries of up to kBatch columns and ask for their first cache lines, so the
  // memory loads overlap; then visit them in the same order (column by column, layer by layer). One loop
  // visits every batch, so f is inlined once, here (flushed from two places, the visit and f stayed out of
  // line and read f's captures through the flush's closure at every entry).
  struct Run {
    const Entry *begin, *end;
    double sx, sy;
    int image;
  };
  constexpr int kBatch = 32;
  Run runs[kBatch];
  if (rx.lo > rx.hi) return;
  // Row by row (a row's wrap, shift and image code worked out once); a full batch ends the gathering
  // mid-row, and the next one resumes at (ix, iy).
  long ix = rx.lo, iy = ry.lo;
  while (iy <= ry.hi) {
    int n = 0;
    for (; iy <= ry.hi && n < kBatch; ++iy, ix = rx.lo) {
      long wy = iy, ky = 0;
      if (wrap_y_) { ky = floor_div(iy, ny_); wy = iy - ky * ny_; }
      else if (iy < iy0_ || iy >= iy0_ + ny_) continue;
      const long row = row_start(wy);
      const double sy = ky * period_y_;
      for (; ix <= rx.hi && n < kBatch; ++ix) {
        long wx = ix, kx = 0;
        if (wrap_x_) { kx = floor_div(ix, nx_); wx = ix - kx * nx_; }
        else if (ix < ix0_ || ix >= ix0_ + nx_) continue;
        const Column& column = columns_[row + wx];
        const long top = std::min<long>(iz_hi, column.layers() - 1), bottom = std::max(0L, iz_lo);
        if (top < bottom) continue;
        const Entry* begin = column.entries.data() + column.start[bottom];
        const Entry* end = column.entries.data() + column.start[top + 1];
        if (begin == end) continue;
        __builtin_prefetch(begin);
        __builtin_prefetch(reinterpret_cast<const char*>(begin) + 64);
        runs[n++] = Run{begin, end, kx * period_x_, sy, image_code(kx, ky)};
      }
      if (ix <= rx.hi) break;  // the batch is full mid-row
    }
    for (int k = 0; k < n; ++k) {
      const Run& run = runs[k];
      for (const Entry* e = run.begin; e != run.end; ++e)
        f(e->index, Vec3(e->x + run.sx, e->y + run.sy, e->z), e->r, run.image);
    }
  }
}

template <class F>
void NeighbourGrid::visit_box(const Vec3& lo, const Vec3& hi, F&& f) const {
  visit_cell_range(x_range(lo.x(), hi.x()), y_range(lo.y(), hi.y()),
                   static_cast<long>(std::floor(lo.z() / h_)), static_cast<long>(std::floor(hi.z() / h_)), f);
}

template <class F, class G>
void NeighbourGrid::visit_column_down(double x, double y, double reach, double z_start, G&& keep_going,
                                      F&& f) const {
  // The columns are looked up once (a fall usually reads two or three layers of each); then layer by
  // layer, in the order visit_cell_range would take them, with the first lines of each run prefetched.
  struct Col {  // a column's layer table, entries and layer count, read once
    const std::uint32_t* start;
    const Entry* entries;
    long layers;
    double sx, sy;
    int image;
  };
  constexpr int kMaxCols = 64;
  Range rx = x_range(x - reach, x + reach), ry = y_range(y - reach, y + reach);
  if ((rx.hi - rx.lo + 1) * (ry.hi - ry.lo + 1) > kMaxCols) {  // not reached with the reach of one grain
    long top = -1;
    for (long iy = ry.lo; iy <= ry.hi; ++iy)
      for (long ix = rx.lo; ix <= rx.hi; ++ix) {
        long wx = ix, wy = iy;
        if (wrap_y_) wy = iy - floor_div(iy, ny_) * ny_;
        else if (iy < iy0_ || iy >= iy0_ + ny_) continue;
        if (wrap_x_) wx = ix - floor_div(ix, nx_) * nx_;
        else if (ix < ix0_ || ix >= ix0_ + nx_) continue;
        top = std::max<long>(top, columns_[column_of(wx, wy)].layers() - 1);
      }
    top = std::min<long>(top, static_cast<long>(std::floor(z_start / h_)));
    for (long iz = top; iz >= 0; --iz) {
      if (!keep_going((iz + 1) * h_)) return;
      visit_cell_range(rx, ry, iz, iz, f);
    }
    return;
  }
  Col cols[kMaxCols];
  int n = 0;
  long top = -1;
  for (long iy = ry.lo; iy <= ry.hi; ++iy) {
    long wy = iy, ky = 0;
    if (wrap_y_) { ky = floor_div(iy, ny_); wy = iy - ky * ny_; }
    else if (iy < iy0_ || iy >= iy0_ + ny_) continue;
    for (long ix = rx.lo; ix <= rx.hi; ++ix) {
      long wx = ix, kx = 0;
      if (wrap_x_) { kx = floor_div(ix, nx_); wx = ix - kx * nx_; }
      else if (ix < ix0_ || ix >= ix0_ + nx_) continue;
      const Column& column = columns_[column_of(wx, wy)];
      if (column.layers() == 0) continue;
      top = std::max<long>(top, column.layers() - 1);
      cols[n++] = Col{column.start.data(), column.entries.data(), column.layers(), kx * period_x_, ky * period_y_,
                      image_code(kx, ky)};
    }
  }
  top = std::min<long>(top, static_cast<long>(std::floor(z_start / h_)));
  for (long iz = top; iz >= 0; --iz) {
    if (!keep_going((iz + 1) * h_)) return;
    for (int k = 0; k < n; ++k)
      if (iz < cols[k].layers) __builtin_prefetch(cols[k].entries + cols[k].start[iz]);
    for (int k = 0; k < n; ++k) {
      const Col& col = cols[k];
      if (iz >= col.layers) continue;
      const Entry* e = col.entries + col.start[iz];
      const Entry* end = col.entries + col.start[iz + 1];
      for (; e != end; ++e) f(e->index, Vec3(e->x + col.sx, e->y + col.sy, e->z), e->r, col.image);
    }
  }
}

}  // namespace btr
