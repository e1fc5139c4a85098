#include "btr/placement/neighbour_grid.h"

#include "btr/scene/size_budget.h"

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include <algorithm>
#include <cstdint>
#include <limits>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string>

namespace btr {

namespace {
constexpr std::size_t kHugePage = std::size_t(2) << 20;
std::size_t round_up(std::size_t n, std::size_t to) { return (n + to - 1) / to * to; }
}  // namespace

void* allocate_large_pages(std::size_t bytes) {
#if defined(__linux__)
  if (bytes >= kLargePageBytes) {
    // Map 2 MiB more than asked, keep a 2 MiB-aligned span of the rounded size and unmap the rest.
    const std::size_t size = round_up(bytes, kHugePage);
    void* raw = ::mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw == MAP_FAILED) throw std::bad_alloc();
    const auto base = reinterpret_cast<std::uintptr_t>(raw);
    const std::uintptr_t aligned = round_up(base, kHugePage);
    if (aligned > base) ::munmap(raw, aligned - base);
    if (base + kHugePage > aligned) ::munmap(reinterpret_cast<void*>(aligned + size), base + kHugePage - aligned);
    ::madvise(reinterpret_cast<void*>(aligned), size, MADV_HUGEPAGE);
    return reinterpret_cast<void*>(aligned);
  }
#endif
  return ::operator new(bytes);
}

void free_large_pages(void* p, std::size_t bytes) noexcept {
#if defined(__linux__)
  if (bytes >= kLargePageBytes) {
    ::munmap(p, round_up(bytes, kHugePage));
    return;
  }
#endif
  ::operator delete(p);
}

void advise_large_pages(void* p, std::size_t bytes) noexcept {
#if defined(__linux__)
  if (bytes < kLargePageBytes) return;
  const auto begin = round_up(reinterpret_cast<std::uintptr_t>(p), kHugePage);
  const auto end = (reinterpret_cast<std::uintptr_t>(p) + bytes) / kHugePage * kHugePage;
  if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)p, (void)bytes;
#endif
}

GridArena::~GridArena() {
  for (const Chunk& c : chunks_) free_large_pages(c.base, c.bytes);
}

void* GridArena::allocate(std::size_t bytes) {
  const std::size_t b = std::max<std::size_t>(8, round_up(bytes, 8));
  if (b > kMaxBlock) return ::operator new(b);
  if (free_.empty()) free_.assign(kMaxBlock / 8 + 1, nullptr);
  if (void* p = free_[b / 8]) {
    free_[b / 8] = *static_cast<void**>(p);
    return p;
  }
  if (static_cast<std::size_t>(end_ - next_) < b) {
    // Chunks from 256 KiB, doubling up to 32 MiB (from 4 MiB on in 2 MiB pages); the rest of the last one is left.
    const std::size_t bytes_chunk = chunks_.empty() ? std::size_t(256) << 10
                                                    : std::min(2 * chunks_.back().bytes, std::size_t(32) << 20);
    void* base = allocate_large_pages(bytes_chunk);
    chunks_.push_back({base, bytes_chunk});
    next_ = static_cast<char*>(base);
    end_ = next_ + bytes_chunk;
  }
  void* p = next_;
  next_ += b;
  return p;
}

void GridArena::deallocate(void* p, std::size_t bytes) noexcept {
  const std::size_t b = std::max<std::size_t>(8, round_up(bytes, 8));
  if (b > kMaxBlock) {
    ::operator delete(p);
    return;
  }
  *static_cast<void**>(p) = free_[b / 8];
  free_[b / 8] = p;
}

NeighbourGrid::NeighbourGrid(int dimension, const Container& c, double r_max)
    : dimension_(dimension), wrap_x_(wraps_x(c)), wrap_y_(wraps_y(c, dimension)), grows_(c.kind == ContainerKind::Open),
      h_(2.0 * r_max) {
  hx_ = hy_ = h_;
  auto span = [&](double length, double& origin, long& n, double& width, bool periodic) {
    origin = -0.5 * length;
    if (periodic) {
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
    case ContainerKind::Mesh:  // its bounding box, centred on the z axis
    case ContainerKind::Periodic:
      span(c.size_x, x0_, nx_, hx_, wrap_x_);
      if (dimension == 3) span(c.size_y, y0_, ny_, hy_, wrap_y_);
      else { y0_ = 0.0; ny_ = 1; }
      period_x_ = c.size_x;
      period_y_ = dimension == 3 ? c.size_y : 0.0;
      break;
    case ContainerKind::HeleShaw:
      span(c.size_x, x0_, nx_, hx_, wrap_x_);
      span(c.gap, y0_, ny_, hy_, false);
      break;
    case ContainerKind::Cylinder:
      span(2.0 * c.radius, x0_, nx_, hx_, false);
      span(2.0 * c.radius, y0_, ny_, hy_, false);
      break;
    case ContainerKind::Drum:
      span(2.0 * c.radius, x0_, nx_, hx_, false);
      if (dimension == 3) span(c.size_y, y0_, ny_, hy_, wrap_y_);
      period_y_ = wrap_y_ ? c.size_y : 0.0;
      break;
  }
  if (dimension == 2) { y0_ = -0.5 * h_; iy0_ = 0; ny_ = 1; hy_ = h_; }
  columns_.assign(static_cast<std::size_t>(nx_ * ny_), Column(arena_.get()));
}

namespace {

// A query over more periods than image codes tell apart (a period far below the grain size).
[[noreturn]] void too_many_images(const char* axis) {
    throw std::length_error(std::string("neighbour query spans more than ") +
                            std::to_string(NeighbourGrid::kMaxImageShift - 2) + " periods in " + axis +
                            ": the period is too small against the grain size");
}

inline void check_images(long lo, long hi, long n, const char* axis) {
  const long limit = (NeighbourGrid::kMaxImageShift - 2) * n;
  if (lo < -limit || hi > limit) too_many_images(axis);
}

// Floor of v as a column index; v must be finite (checked by the caller for inserted centres; a
// query box is built from finite centres).
long index_of(double v) { return static_cast<long>(std::floor(v)); }

}  // namespace

NeighbourGrid::Range NeighbourGrid::x_range(double lo, double hi) const {
  const Range r{index_of((lo - x0_) / hx_), index_of((hi - x0_) / hx_)};
  if (wrap_x_) check_images(r.lo, r.hi, nx_, "x");
  return r;
}

NeighbourGrid::Range NeighbourGrid::y_range(double lo, double hi) const {
  if (dimension_ == 2) return {0, 0};
  const Range r{index_of((lo - y0_) / hy_), index_of((hi - y0_) / hy_)};
  if (wrap_y_) check_images(r.lo, r.hi, ny_, "y");
  return r;
}

void NeighbourGrid::prefetch(double x, double y, double reach, double z, int stage) const {
  if (!std::isfinite(x) || !std::isfinite(y)) return;
  const Range rx = x_range(x - reach, x + reach), ry = y_range(y - reach, y + reach);
  const long iz = std::isfinite(z) ? std::max(0L, index_of(z / h_)) : std::numeric_limits<long>::max();
  for (long iy = ry.lo; iy <= ry.hi; ++iy) {
    long wy = iy;
    if (wrap_y_) wy = iy - floor_div(iy, ny_) * ny_;
    else if (iy < iy0_ || iy >= iy0_ + ny_) continue;
    for (long ix = rx.lo; ix <= rx.hi; ++ix) {
      long wx = ix;
      if (wrap_x_) wx = ix - floor_div(ix, nx_) * nx_;
      else if (ix < ix0_ || ix >= ix0_ + nx_) continue;
      const Column& column = columns_[column_of(wx, wy)];
      if (stage == 0) {
        __builtin_prefetch(&column);
        continue;
      }
      const long layers = column.layers();
      if (layers == 0) continue;
      const long top = std::min(layers - 1, iz);
      if (stage == 1) {
        __builtin_prefetch(column.start.data() + std::max(0L, top - 1));
        continue;
      }
      const char* begin = reinterpret_cast<const char*>(column.entries.data() + column.start[std::max(0L, top - 1)]);
      const char* end = reinterpret_cast<const char*>(column.entries.data() + column.start[top + 1]);
      for (int line = 0; line < 8 && begin + 64 * line < end; ++line) __builtin_prefetch(begin + 64 * line);
    }
  }
}

void NeighbourGrid::reserve(std::int64_t n) {
  if (grows_ || n <= 0) return;
  const double share = 1.25 * double(n) / double(columns_.size());
  if (share < 2.0 || share > 1e6) return;
  const auto room = static_cast<std::size_t>(std::ceil(share));
  for (Column& c : columns_)
    if (c.entries.capacity() < room) c.entries.reserve(room);
}

// An open floor's grid grows towards the column that is outside it, on that side only, at least
// doubling its extent on that axis (amortised constant cost per grain as a heap spreads). A grid that
// would exceed its budget (a grain dropped far from all the others) is refused, not allocated.
void NeighbourGrid::grow_to(long ix, long iy) {
  auto extend = [](long i, long& i0, long& n) {
    if (i < i0) {
      const long hi = i0 + n;
      i0 = std::min(i, i0 - n);
      n = hi - i0;
    } else if (i >= i0 + n) {
      n = std::max(i - i0 + 1, 2 * n);
    }
  };
  long new_ix0 = ix0_, new_nx = nx_, new_iy0 = iy0_, new_ny = ny_;
  extend(ix, new_ix0, new_nx);
  if (dimension_ == 3) extend(iy, new_iy0, new_ny);
  // The same rule as the scene's up-front check (size_budget.h): a grid the scene's footprint allowed never
  // hits it; a grid larger than half this machine's memory is refused instead of allocated.
  const double budget = std::max(double(1L << 20), 0.5 * machine_memory_bytes() / double(sizeof(Column)));
  if (double(new_nx) * double(new_ny) > budget) {
    std::ostringstream why;
    why << "centre " << ix - ix0_ << ", " << iy - iy0_ << " cells from the grid's corner: the open floor's neighbour "
        << "grid would need " << double(new_nx) * double(new_ny) << " columns (budget " << budget
        << "): a drop far away from all the other grains";
    throw std::length_error(why.str());
  }
  std::vector<Column, LargePageAllocator<Column>> grown(static_cast<std::size_t>(new_nx * new_ny), Column(arena_.get()));
  for (long y = iy0_; y < iy0_ + ny_; ++y)
    for (long x = ix0_; x < ix0_ + nx_; ++x)
      grown[(x - new_ix0) + new_nx * (y - new_iy0)] = std::move(columns_[column_of(x, y)]);
  columns_ = std::move(grown);
  ix0_ = new_ix0; nx_ = new_nx; iy0_ = new_iy0; ny_ = new_ny;
}

void NeighbourGrid::insert(std::int32_t index, const Vec3& x, double r) {
  if (!x.allFinite()) {
    std::ostringstream why;
    why << "grain index " << index << " has a non-finite centre (" << x.x() << ", " << x.y() << ", " << x.z() << ")";
    throw std::out_of_range(why.str());
  }
  const double ux = (x.x() - x0_) / hx_, uy = dimension_ == 3 ? (x.y() - y0_) / hy_ : 0.0;
  long ix = index_of(ux), iy = index_of(uy);
  if (grows_) {
    if (ix < ix0_ || ix >= ix0_ + nx_ || iy < iy0_ || iy >= iy0_ + ny_) grow_to(ix, iy);
  } else {
    // A centre on the grid's edge is outside by round-off only; farther out, the grain escaped.
    auto bound = [&](double u, long i, long i0, long n, bool wrap, const char* axis) {
      if (wrap) return i - floor_div(i, n) * n;
      constexpr double kEdge = 1e-9;  // in cell widths
      if (u < double(i0) - kEdge || u > double(i0 + n) + kEdge) {
        std::ostringstream why;
        why << "grain index " << index << " at (" << x.x() << ", " << x.y() << ", " << x.z() << ") is outside the "
            << "container's grid in " << axis;
        throw std::out_of_range(why.str());
      }
      return std::clamp(i, i0, i0 + n - 1);
    };
    ix = bound(ux, ix, ix0_, nx_, wrap_x_, "x");
    iy = bound(uy, iy, iy0_, ny_, wrap_y_, "y");
  }
  const long iz = std::max(0L, index_of(x.z() / h_));
  Column& column = columns_[column_of(ix, iy)];
  if (column.start.empty()) column.start.push_back(0);
  if (column.layers() <= iz) {
    const std::uint32_t end = column.start.back();  // a copy: resize may move the storage
    column.start.resize(static_cast<std::size_t>(iz) + 2, end);
  }
  // At the end of layer iz; the layers above (usually none: grains mostly land on top) move up by one.
  column.entries.insert(column.entries.begin() + column.start[iz + 1], Entry{x.x(), x.y(), x.z(), r, index});
  for (std::size_t k = static_cast<std::size_t>(iz) + 1; k < column.start.size(); ++k) ++column.start[k];
}

}  // namespace btr
