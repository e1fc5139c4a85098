#include "btr/measures/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

#include "btr/placement/pair_search.h"

namespace btr {
namespace {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------- volumes

// Area of the disk of radius rho about the origin inside [0, X] x [0, Y], for X, Y >= 0.
double corner_area(double X, double Y, double rho) {
  X = std::min(X, rho);
  Y = std::min(Y, rho);
  if (X * X + Y * Y <= rho * rho) return X * Y;
  const double r2 = rho * rho;
  auto S = [&](double x) {  // integral of sqrt(rho^2 - t^2) from 0 to x
    return 0.5 * (x * std::sqrt(std::max(0.0, r2 - x * x)) + r2 * std::asin(std::clamp(x / rho, -1.0, 1.0)));
  };
  const double x0 = std::sqrt(std::max(0.0, r2 - Y * Y));
  return Y * x0 + S(X) - S(x0);
}

double signed_corner_area(double X, double Y, double rho) {
  double a = corner_area(std::abs(X), std::abs(Y), rho);
  return ((X < 0) != (Y < 0)) ? -a : a;
}

// Area of the disk (centre (cx, cy), radius rho) inside [x0, x1] x [y0, y1], by inclusion-exclusion
// of signed corner areas.
double disk_rect_area(double cx, double cy, double rho, double x0, double x1, double y0, double y1) {
  if (rho <= 0.0) return 0.0;
  const double a = x0 - cx, b = x1 - cx, c = y0 - cy, d = y1 - cy;
  double area = signed_corner_area(b, d, rho) - signed_corner_area(a, d, rho) - signed_corner_area(b, c, rho) +
                signed_corner_area(a, c, rho);
  return std::max(0.0, area);
}

// Volume of a sphere of radius r between the heights t = a and t = b relative to its centre.
double sphere_slab(double r, double a, double b) {
  a = std::clamp(a, -r, r);
  b = std::clamp(b, -r, r);
  if (b <= a) return 0.0;
  auto F = [&](double t) { return r * r * t - t * t * t / 3.0; };
  return kPi * (F(b) - F(a));
}

// Area of a disk of radius r between t = a and t = b relative to its centre.
double disk_slab(double r, double a, double b) {
  a = std::clamp(a, -r, r);
  b = std::clamp(b, -r, r);
  if (b <= a) return 0.0;
  auto F = [&](double t) { return t * std::sqrt(std::max(0.0, r * r - t * t)) + r * r * std::asin(t / r); };
  return F(b) - F(a);
}

struct GaussLegendre {
  static constexpr int kN = 32;
  std::array<double, kN> x{}, w{};
  GaussLegendre() {
    for (int i = 0; i < kN; ++i) {
      double z = std::cos(kPi * (i + 0.75) / (kN + 0.5)), dp = 0.0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1.0, p1 = 0.0;
        for (int k = 1; k <= kN; ++k) {
          double p2 = p1;
          p1 = p0;
          p0 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p2) / k;
        }
        dp = kN * (z * p0 - p1) / (z * z - 1.0);
        double dz = p0 / dp;
        z -= dz;
        if (std::abs(dz) < 1e-16) break;
      }
      x[i] = z;
      w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
  }
};

// Sphere cut by vertical box sides: integrate the exact disk-rectangle area over z = zc + r sin(theta)
// (dz = r cos(theta) dtheta removes the square-root ends), split where the section radius crosses the
// distance to a side line or a corner, where the integrand has a kink.
double sphere_box_quadrature(const Grain& g, const Box& box, double z1, double z2) {
  static const GaussLegendre gl;
  const double r = g.r, cx = g.x.x(), cy = g.x.y(), zc = g.x.z();
  const double t1 = std::asin(std::clamp((z1 - zc) / r, -1.0, 1.0));
  const double t2 = std::asin(std::clamp((z2 - zc) / r, -1.0, 1.0));
  std::vector<double> cuts{t1, t2};
  const double dx[2] = {std::abs(box.lo.x() - cx), std::abs(box.hi.x() - cx)};
  const double dy[2] = {std::abs(box.lo.y() - cy), std::abs(box.hi.y() - cy)};
  std::vector<double> radii{dx[0], dx[1], dy[0], dy[1]};
  for (double a : dx)
    for (double b : dy) radii.push_back(std::hypot(a, b));
  for (double rho : radii) {
    if (rho <= 0.0 || rho >= r) continue;
    double t = std::acos(rho / r);
    for (double tt : {t, -t})
      if (tt > t1 && tt < t2) cuts.push_back(tt);
  }
  std::sort(cuts.begin(), cuts.end());
  double volume = 0.0;
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    const double a = cuts[k], b = cuts[k + 1];
    if (b <= a) continue;
    // t = a + (b - a) s(u), s = 3u^2 - 2u^3: the (t - t_k)^(3/2) kinks at the ends become smooth in u.
    double sum = 0.0;
    for (int i = 0; i < GaussLegendre::kN; ++i) {
      const double u = 0.5 * (1.0 + gl.x[i]);
      const double t = a + (b - a) * u * u * (3.0 - 2.0 * u);
      const double dt_du = (b - a) * 6.0 * u * (1.0 - u);
      const double rho = r * std::cos(t);
      sum += 0.5 * gl.w[i] * dt_du * disk_rect_area(cx, cy, rho, box.lo.x(), box.hi.x(), box.lo.y(), box.hi.y()) * rho;
    }
    volume += sum;  // dz = r cos(t) dt = rho dt
  }
  return volume;
}

bool in_window(const Vec3& x, int dimension, const Box& w) {
  if (x.x() < w.lo.x() || x.x() > w.hi.x() || x.z() < w.lo.z() || x.z() > w.hi.z()) return false;
  return dimension == 2 || (x.y() >= w.lo.y() && x.y() <= w.hi.y());
}

// Least-squares line y = a + b x through points added one by one.
struct LineFit {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  void add(double x, double y) { n += 1, sx += x, sy += y, sxx += x * x, sxy += x * y; }
  bool ok() const { return n >= 3 && n * sxx - sx * sx > 0.0; }  // 3 points at 2 x or more
  double slope() const { return (n * sxy - sx * sy) / (n * sxx - sx * sx); }
};

// ---------------------------------------------------------------- free surface

// The free surface seen from above: the lateral rectangle cut into columns about one largest diameter
// wide (at least one), each with the highest grain top among the grains centred in it (0 if none).
struct HeightMap {
  int nx = 1, ny = 1;
  std::vector<double> ex, ey;  // column edges (2D: ey = {0, 1})
  std::vector<double> top;     // [j * nx + i]
};

HeightMap height_map(const Grains& grains, int dimension, double x0, double x1, double y0, double y1, double width,
                     int max_columns) {
  HeightMap h;
  auto edges = [&](double a, double b, int& n, std::vector<double>& e) {
    // at least `width` wide: a narrower column can hold no grain centre and read as a hole in the surface
    n = std::clamp(static_cast<int>(std::floor((b - a) / width + 1e-9)), 1, max_columns);
    e.resize(n + 1);
    for (int k = 0; k <= n; ++k) e[k] = a + (b - a) * k / n;
  };
  edges(x0, x1, h.nx, h.ex);
  if (dimension == 3) edges(y0, y1, h.ny, h.ey);
  else h.ny = 1, h.ey = {0.0, 1.0};
  h.top.assign(std::size_t(h.nx) * h.ny, 0.0);
  const double wx = (x1 - x0) / h.nx, wy = dimension == 3 ? (y1 - y0) / h.ny : 1.0;
  for (const Grain& g : grains) {
    if (g.x.x() < x0 || g.x.x() > x1) continue;
    if (dimension == 3 && (g.x.y() < y0 || g.x.y() > y1)) continue;
    const int i = std::clamp(static_cast<int>((g.x.x() - x0) / wx), 0, h.nx - 1);
    const int j = dimension == 3 ? std::clamp(static_cast<int>((g.x.y() - y0) / wy), 0, h.ny - 1) : 0;
    double& t = h.top[std::size_t(j) * h.nx + i];
    t = std::max(t, g.x.z() + g.r);
  }
  return h;
}

}  // namespace

double mean_surface_height(const Grains& grains, int dimension, const Container& container, double width) {
  if (grains.empty()) return 0.0;
  double x0, x1, y0 = 0.0, y1 = 0.0;
  switch (container.kind) {
    case ContainerKind::Box:
    case ContainerKind::Periodic:
      x1 = 0.5 * container.size_x, y1 = 0.5 * container.size_y;
      break;
    case ContainerKind::HeleShaw: x1 = 0.5 * container.size_x, y1 = 0.5 * container.gap; break;
    case ContainerKind::Cylinder: x1 = y1 = container.radius / std::sqrt(2.0); break;
    default:
      x1 = y1 = 0.0;
      for (const Grain& g : grains) x1 = std::max(x1, std::abs(g.x.x())), y1 = std::max(y1, std::abs(g.x.y()));
  }
  x0 = -x1, y0 = -y1;
  const HeightMap h = height_map(grains, dimension, x0, x1, y0, y1, width, 1 << 20);
  double sum = 0.0;
  int n = 0;
  for (double t : h.top)
    if (t > 0.0) sum += t, ++n;
  return n ? sum / n : 0.0;
}

BedHeightMeasures bed_height_measures(const Grains& grains, int dimension, const Container& container, double width) {
  BedHeightMeasures m;
  m.mean_height = mean_surface_height(grains, dimension, container, width);
  double footprint = std::numeric_limits<double>::quiet_NaN();
  switch (container.kind) {
    case ContainerKind::Box:
    case ContainerKind::Periodic: footprint = dimension == 3 ? container.size_x * container.size_y : container.size_x; break;
    case ContainerKind::HeleShaw: footprint = container.size_x * container.gap; break;
    case ContainerKind::Cylinder: footprint = M_PI * container.radius * container.radius; break;
    default: break;
  }
  const double volume = solid_volume(grains, dimension);
  m.packing_fraction = m.mean_height > 0.0 ? volume / (footprint * m.mean_height) : 0.0;
  return m;
}

namespace {

struct Span {
  double extent = 0.0, height = 0.0;  // (edge[last + 1] - edge[first]) and the least height over it
  int first = 0, last = -1;
};

// Largest rectangle under a histogram of columns with the given edges (heights <= 0 never count).
Span largest_rectangle(const std::vector<double>& height, const std::vector<double>& edge) {
  const int n = static_cast<int>(height.size());
  std::vector<int> left(n), right(n), stack;
  for (int j = 0; j < n; ++j) {
    while (!stack.empty() && height[stack.back()] >= height[j]) stack.pop_back();
    left[j] = stack.empty() ? 0 : stack.back() + 1;
    stack.push_back(j);
  }
  stack.clear();
  for (int j = n - 1; j >= 0; --j) {
    while (!stack.empty() && height[stack.back()] >= height[j]) stack.pop_back();
    right[j] = stack.empty() ? n - 1 : stack.back() - 1;
    stack.push_back(j);
  }
  Span best;
  for (int j = 0; j < n; ++j) {
    if (!(height[j] > 0.0)) continue;
    const double extent = edge[right[j] + 1] - edge[left[j]];
    if (extent * height[j] > best.extent * best.height) best = {extent, height[j], left[j], right[j]};
  }
  return best;
}

double fill_fraction(const Grains& grains, int dimension, const BulkMeasures& m) {
  double solid = 0.0;
  for (const Grain& g : grains)
    solid += m.slab ? grain_volume_in_slab(g, dimension, m.window.lo.z(), m.window.hi.z())
                    : grain_volume_in_box(g, dimension, m.window);
  return solid / m.window_volume;
}

std::string fmt(const char* format, double a, double b = 0.0) {
  char buf[200];
  std::snprintf(buf, sizeof buf, format, a, b);
  return buf;
}

}  // namespace

// ---------------------------------------------------------------- public

bool in_bulk_window(const BulkMeasures& bulk, const Vec3& x, int dimension) {
  return bulk.slab ? (x.z() >= bulk.window.lo.z() && x.z() <= bulk.window.hi.z()) : in_window(x, dimension, bulk.window);
}

std::vector<int> coordination_numbers(const Grains& grains, int dimension, const Container& container,
                                      double contact_tol) {
  std::vector<int> z(grains.size(), 0);
  if (grains.empty()) return z;
  const double r_max = max_radius(grains);
  const PairSearch pairs(grains, dimension, container, 2.0 * r_max * (1.0 + 2.0 * contact_tol) * 1.0001);
  pairs.for_each_pair([&](std::size_t a, std::size_t b, const Vec3& d) {
    const auto [i, j] = std::minmax(a, b);  // the radii subtracted in index order, as always
    const double gap = d.norm() - grains[i].r - grains[j].r;
    if (gap < contact_tol * std::min(grains[i].r, grains[j].r)) {
      ++z[i];
      ++z[j];
    }
  });
  return z;
}

double grain_volume_in_slab(const Grain& g, int dimension, double z_lo, double z_hi) {
  const double a = z_lo - g.x.z(), b = z_hi - g.x.z();
  return dimension == 2 ? disk_slab(g.r, a, b) : sphere_slab(g.r, a, b);
}

double grain_volume_in_box(const Grain& g, int dimension, const Box& box) {
  const double r = g.r;
  const double z1 = std::max(box.lo.z(), g.x.z() - r), z2 = std::min(box.hi.z(), g.x.z() + r);
  if (z2 <= z1) return 0.0;
  if (dimension == 2)
    return disk_rect_area(g.x.x(), g.x.z(), r, box.lo.x(), box.hi.x(), box.lo.z(), box.hi.z());
  const double x = g.x.x(), y = g.x.y();
  if (x + r <= box.lo.x() || x - r >= box.hi.x() || y + r <= box.lo.y() || y - r >= box.hi.y()) return 0.0;
  if (x - r >= box.lo.x() && x + r <= box.hi.x() && y - r >= box.lo.y() && y + r <= box.hi.y())
    return sphere_slab(r, z1 - g.x.z(), z2 - g.x.z());
  return sphere_box_quadrature(g, box, z1, z2);
}

double packing_fraction_in_box(const Grains& grains, int dimension, const Box& box) {
  double volume = (box.hi.x() - box.lo.x()) * (box.hi.z() - box.lo.z());
  if (dimension == 3) volume *= box.hi.y() - box.lo.y();
  double solid = 0.0;
  for (const Grain& g : grains) solid += grain_volume_in_box(g, dimension, box);
  return solid / volume;
}

BulkMeasures bulk_measures(const Grains& grains, int dimension, const Container& container,
                           const MetricsOptions& options, const std::vector<int>* coordination) {
  BulkMeasures m;
  if (grains.empty()) {
    m.note = "no grains";
    return m;
  }
  if (container.kind == ContainerKind::Drum) {
    // A box under the surface would reach below the drum's curved wall, where there are no grains.
    m.note = "no bulk window in a drum (its floor is the curved wall); see the drum measures of `btr drum`";
    return m;
  }
  if (container.kind == ContainerKind::Mesh) {
    // A box bounded by the grains' extent would reach beyond a hopper's sloping walls.
    m.note = "no bulk window in a mesh container (its walls have any shape); measure a window of your own";
    return m;
  }
  const double d = 2.0 * max_radius(grains);
  const double margin = options.margin_diameters * d;
  const bool three = dimension == 3;

  if (container.kind == ContainerKind::Periodic) {
    const double lx = container.size_x, ly = three ? container.size_y : 0.0;
    const HeightMap h = height_map(grains, dimension, -0.5 * lx, 0.5 * lx, -0.5 * ly, 0.5 * ly, d, 1 << 20);
    const double surface = *std::min_element(h.top.begin(), h.top.end());
    m.slab = true;
    m.window.lo = Vec3(-0.5 * lx, -0.5 * ly, margin);
    m.window.hi = Vec3(0.5 * lx, 0.5 * ly, surface - margin);
    m.window_volume = lx * (three ? ly : 1.0) * (m.window.hi.z() - m.window.lo.z());
    if (!(m.window.hi.z() > m.window.lo.z())) {
      m.note = fmt("bed too shallow for a bulk window: lowest surface column at z = %.4g m, margin %.4g m",
                   surface, margin);
      return m;
    }
    m.note = fmt("z-slab over the whole period, z in [%.6g, %.6g] m", m.window.lo.z(), m.window.hi.z());
  } else {
    // Lateral bounds of the window: the walls, or the extent of the grains, less the margin.
    double bx0, bx1, by0 = 0.0, by1 = 0.0;
    std::string how;
    switch (container.kind) {
      case ContainerKind::Box:
        bx0 = -0.5 * container.size_x + margin, bx1 = -bx0;
        by0 = -0.5 * container.size_y + margin, by1 = -by0;
        break;
      case ContainerKind::HeleShaw:
        bx0 = -0.5 * container.size_x + margin, bx1 = -bx0;
        by0 = -0.5 * container.gap, by1 = -by0;  // the plates are the cell itself: the window spans the gap
        how = "; it spans the whole Hele-Shaw gap";
        break;
      case ContainerKind::Cylinder: {
        double s = (container.radius - margin) / std::sqrt(2.0);  // square inscribed in the cylinder
        bx0 = -s, bx1 = s, by0 = -s, by1 = s;
        break;
      }
      default: {  // open floor: bounded by the grains themselves
        bx0 = by0 = std::numeric_limits<double>::max();
        bx1 = by1 = -bx0;
        for (const Grain& g : grains) {
          bx0 = std::min(bx0, g.x.x() - g.r), bx1 = std::max(bx1, g.x.x() + g.r);
          by0 = std::min(by0, g.x.y() - g.r), by1 = std::max(by1, g.x.y() + g.r);
        }
        bx0 += margin, bx1 -= margin, by0 += margin, by1 -= margin;
      }
    }
    if (!three) by0 = by1 = 0.0;
    if (!(bx1 > bx0) || (three && !(by1 > by0))) {
      m.note = "container too narrow for a bulk window";
      return m;
    }
    // The column-aligned box of largest volume whose top stays `margin` below every column top.
    const int cap = three ? 200 : 2000;  // columns per side; wider columns beyond that keep the search cheap
    const HeightMap h = height_map(grains, dimension, bx0, bx1, by0, by1, d, cap);
    double best = 0.0;
    std::vector<double> least(h.ny), avail(h.ny);
    for (int i0 = 0; i0 < h.nx; ++i0) {
      std::fill(least.begin(), least.end(), std::numeric_limits<double>::max());
      for (int i1 = i0; i1 < h.nx; ++i1) {
        for (int j = 0; j < h.ny; ++j) {
          least[j] = std::min(least[j], h.top[std::size_t(j) * h.nx + i1]);
          avail[j] = least[j] - 2.0 * margin;  // window from z = margin to (column top - margin)
        }
        const Span span = largest_rectangle(avail, h.ey);
        const double vol = (h.ex[i1 + 1] - h.ex[i0]) * span.extent * span.height;
        if (vol > best) {
          best = vol;
          m.window.lo = Vec3(h.ex[i0], three ? h.ey[span.first] : 0.0, margin);
          m.window.hi = Vec3(h.ex[i1 + 1], three ? h.ey[span.last + 1] : 0.0, margin + span.height);
          m.window_volume = three ? vol : (h.ex[i1 + 1] - h.ex[i0]) * span.height;
        }
      }
    }
    if (best <= 0.0) {
      m.note = "packing too shallow for a bulk window under the free surface";
      return m;
    }
    m.note = fmt("box window x in [%.6g, %.6g] m", m.window.lo.x(), m.window.hi.x()) +
             (three ? fmt(", y in [%.6g, %.6g] m", m.window.lo.y(), m.window.hi.y()) : "") +
             fmt(", z in [%.6g, %.6g] m", m.window.lo.z(), m.window.hi.z()) + how;
  }

  m.packing_fraction = fill_fraction(grains, dimension, m);
  std::vector<int> computed;
  if (!coordination || coordination->size() != grains.size())
    computed = coordination_numbers(grains, dimension, container, options.contact_tol);
  const std::vector<int>& z = computed.empty() ? *coordination : computed;
  std::int64_t total = 0;
  for (std::size_t i = 0; i < grains.size(); ++i) {
    if (!in_bulk_window(m, grains[i].x, dimension)) continue;
    ++m.grains_in_window;
    total += z[i];
    if (static_cast<std::size_t>(z[i]) >= m.coordination_histogram.size())
      m.coordination_histogram.resize(z[i] + 1, 0);
    ++m.coordination_histogram[z[i]];
  }
  if (m.grains_in_window == 0) {
    m.note += "; no grain centre inside the window";
    return m;
  }
  m.mean_coordination = double(total) / double(m.grains_in_window);
  m.valid = true;
  return m;
}

namespace {

// Profile bins of |distance| (one largest diameter wide), in order of distance, empty bins kept as
// top < 0 so the pile can stop at the first gap.
std::vector<ProfilePoint> binned_profile(const std::vector<ProfilePoint>& samples, double width) {
  std::vector<ProfilePoint> best;
  for (const ProfilePoint& s : samples) {
    const std::size_t bin = static_cast<std::size_t>(s.distance / width);
    if (bin >= best.size()) best.resize(bin + 1, {0.0, -1.0});
    if (s.top > best[bin].top) best[bin] = s;
  }
  return best;
}

struct Flank {
  bool ok = false;
  double angle = 0.0;
  int points = 0;
  double foot = 0.0;  // distance of the last bin of the pile run that was looked at
  FlankLine line;
};

// The flank of one side: walk from the apex bin outwards; fit from the first bin at or below hi to the
// last bin before the profile falls below lo or meets an empty bin.
Flank fit_flank(const std::vector<ProfilePoint>& bins, double lo, double hi) {
  Flank f;
  std::size_t apex = 0;
  for (std::size_t b = 0; b < bins.size(); ++b)
    if (bins[b].top > bins[apex].top) apex = b;
  LineFit fit;
  double first_fitted = 0.0, last_fitted = 0.0;
  f.foot = bins.empty() ? 0.0 : bins[apex].distance;
  for (std::size_t b = apex; b < bins.size(); ++b) {
    const ProfilePoint& p = bins[b];
    if (p.top < lo) break;  // the foot of the pile, or a gap (empty bins have top < 0)
    f.foot = p.distance;
    if (p.top > hi) continue;
    if (fit.n == 0) first_fitted = p.distance;
    last_fitted = p.distance;
    fit.add(p.distance, p.top);
  }
  f.points = static_cast<int>(fit.n);
  if (!fit.ok()) return f;
  f.angle = std::atan(-fit.slope()) * 180.0 / kPi;
  f.ok = true;
  f.line = {true, f.angle, (fit.sy - fit.slope() * fit.sx) / fit.n, first_fitted, last_fitted};
  return f;
}

std::int64_t grains_beyond(const std::vector<ProfilePoint>& samples, double foot, double width) {
  std::int64_t k = 0;
  for (const ProfilePoint& s : samples) k += s.distance > foot + width;
  return k;
}

}  // namespace

std::vector<ProfilePoint> surface_profile(const Grains& grains, const std::vector<double>& distance) {
  if (grains.empty()) return {};
  const double width = 2.0 * max_radius(grains);
  const double lo = *std::min_element(distance.begin(), distance.end());
  std::vector<ProfilePoint> shifted(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) shifted[i] = {distance[i] - lo, grains[i].x.z() + grains[i].r};
  std::vector<ProfilePoint> out;
  for (ProfilePoint p : binned_profile(shifted, width))
    if (p.top >= 0.0) out.push_back({p.distance + lo, p.top});
  return out;
}

HeapMeasures heap_measures(const Grains& grains, int dimension, double source_x, double source_y,
                           bool by_sides) {
  HeapMeasures h;
  h.by_sides = by_sides;
  if (grains.empty()) {
    h.note = "no grains";
    return h;
  }
  const double width = 2.0 * max_radius(grains);
  for (const Grain& g : grains) h.height = std::max(h.height, g.x.z() + g.r);
  const double lo = HeapMeasures::kLowFraction * h.height, hi = HeapMeasures::kHighFraction * h.height;
  std::vector<double> coord(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i)
    coord[i] = by_sides ? grains[i].x.x() - source_x
                        : std::hypot(grains[i].x.x() - source_x, dimension == 3 ? grains[i].x.y() - source_y : 0.0);
  h.profile = surface_profile(grains, coord);
  if (!by_sides) {
    std::vector<ProfilePoint> samples(grains.size());
    for (std::size_t i = 0; i < grains.size(); ++i) samples[i] = {coord[i], grains[i].x.z() + grains[i].r};
    const Flank f = fit_flank(binned_profile(samples, width), lo, hi);
    h.profile_points = f.points;
    h.grains_beyond_flank = grains_beyond(samples, f.foot, width);
    h.valid = f.ok;
    h.angle_deg = f.angle;
    h.line_radial = f.line;
    if (!h.valid) h.note = "fewer than 3 profile points on the flank between 20% and 80% of the height";
    return h;
  }
  std::vector<ProfilePoint> left, right;
  for (std::size_t i = 0; i < grains.size(); ++i)
    (coord[i] < 0 ? left : right).push_back({std::abs(coord[i]), grains[i].x.z() + grains[i].r});
  const Flank fl = fit_flank(binned_profile(left, width), lo, hi);
  const Flank fr = fit_flank(binned_profile(right, width), lo, hi);
  h.profile_points = fl.points + fr.points;
  h.grains_beyond_flank = grains_beyond(left, fl.foot, width) + grains_beyond(right, fr.foot, width);
  h.angle_left_deg = fl.angle, h.angle_right_deg = fr.angle;
  h.left_valid = fl.ok, h.right_valid = fr.ok;
  h.line_left = fl.line, h.line_right = fr.line;
  // A heap built against an end wall (a Hele-Shaw cell fed at a corner) has one flank only: it is
  // measured on the side that has one.
  h.valid = fl.ok || fr.ok;
  if (fl.ok && fr.ok) h.angle_deg = 0.5 * (h.angle_left_deg + h.angle_right_deg);
  else if (h.valid) {
    h.angle_deg = fl.ok ? fl.angle : fr.angle;
    h.note = std::string("one flank only (the ") + (fl.ok ? "left" : "right") + " side of the axis)";
  } else {
    h.note = "fewer than 3 profile points on both flanks between 20% and 80% of the height";
  }
  return h;
}

RadialDistribution radial_distribution(const Grains& grains, int dimension, const Container& container,
                                       const BulkMeasures& bulk, const MetricsOptions& options) {
  RadialDistribution out;
  if (grains.empty()) return out;
  double d = 0.0;
  for (const Grain& g : grains) d += 2.0 * g.r;
  d /= double(grains.size());
  const int nbins = std::max(1, static_cast<int>(std::lround(options.rdf_max_d / options.rdf_bin_d)));
  const double bin = options.rdf_bin_d * d, reach = nbins * bin;
  out.r_over_d.resize(nbins);
  for (int k = 0; k < nbins; ++k) out.r_over_d[k] = (k + 0.5) * options.rdf_bin_d;
  if (!bulk.valid || bulk.grains_in_window == 0 || !(bulk.window_volume > 0.0)) return out;
  std::vector<double> counts(nbins, 0.0);
  std::vector<char> centre(grains.size());
  std::int64_t centres = 0;
  for (std::size_t i = 0; i < grains.size(); ++i) centres += centre[i] = in_bulk_window(bulk, grains[i].x, dimension);
  // Cells up to a third of the reach wide (never narrower than a largest diameter): fewer needless pairs.
  constexpr int kCellsPerReach = 3;
  const double reach2 = reach * reach;
  const PairSearch pairs(grains, dimension, container, reach, kCellsPerReach);
  pairs.for_each_pair([&](std::size_t i, std::size_t j, const Vec3& d) {
    const double r2 = d.squaredNorm();
    if (r2 >= reach2) return;
    const int k = static_cast<int>(std::sqrt(r2) / bin);
    if (k < nbins) counts[k] += centre[i] + centre[j];  // each pair counts once per window grain in it
  });
  const double density = double(centres) / bulk.window_volume;
  out.g.resize(nbins);
  for (int k = 0; k < nbins; ++k) {
    const double a = k * bin, b = (k + 1) * bin;
    const double shell = dimension == 3 ? 4.0 / 3.0 * kPi * (b * b * b - a * a * a) : kPi * (b * b - a * a);
    out.g[k] = counts[k] / (double(centres) * density * shell);
  }
  out.valid = true;
  return out;
}

namespace {

// Means of the per-grain values c over the grains marked large and those marked small.
struct GroupMeans {
  double large = 0.0, small = 0.0;
  std::int64_t n_large = 0, n_small = 0;
};

GroupMeans group_means(const std::vector<double>& c, const std::vector<char>& large, const std::vector<char>& small) {
  GroupMeans m;
  double sl = 0, ss = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (large[i]) sl += c[i], ++m.n_large;
    if (small[i]) ss += c[i], ++m.n_small;
  }
  if (m.n_large) m.large = sl / m.n_large;
  if (m.n_small) m.small = ss / m.n_small;
  return m;
}

SegregationIndex segregation_of(const Grains& grains, const std::vector<double>& c) {
  SegregationIndex s;
  std::map<int, std::pair<double, std::int64_t>> by_species;  // sum of radii, count
  for (const Grain& g : grains) {
    auto& e = by_species[g.species];
    e.first += g.r, e.second += 1;
  }
  std::vector<char> large(grains.size(), 0), small(grains.size(), 0);
  if (by_species.size() >= 2) {
    int ks = by_species.begin()->first, kl = ks;
    for (const auto& [k, e] : by_species) {
      const double m = e.first / e.second;
      if (m < by_species[ks].first / by_species[ks].second) ks = k;
      if (m > by_species[kl].first / by_species[kl].second) kl = k;
    }
    if (by_species[ks].first / by_species[ks].second == by_species[kl].first / by_species[kl].second) {
      s.basis = "all species have the same mean radius";
      return s;
    }
    for (std::size_t i = 0; i < grains.size(); ++i)
      large[i] = grains[i].species == kl, small[i] = grains[i].species == ks;
    s.basis = "species " + std::to_string(kl) + " (large) vs " + std::to_string(ks) + " (small)";
  } else {
    if (grains.empty()) {
      s.basis = "no grains";
      return s;
    }
    std::vector<double> r(grains.size());
    for (std::size_t i = 0; i < grains.size(); ++i) r[i] = grains[i].r;
    const auto [mn, mx] = std::minmax_element(r.begin(), r.end());
    if (*mx <= *mn * 1.05) {
      s.basis = "one size (radii within 5 %)";
      return s;
    }
    std::vector<double> sorted = r;
    const std::size_t n = sorted.size();
    std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.end());
    double median = sorted[n / 2];
    if (n % 2 == 0) median = 0.5 * (median + *std::max_element(sorted.begin(), sorted.begin() + n / 2));
    for (std::size_t i = 0; i < n; ++i) large[i] = r[i] > median, small[i] = r[i] <= median;
    s.basis = "radius above vs below the median";
  }
  const GroupMeans g = group_means(c, large, small);
  if (g.n_large == 0 || g.n_small == 0) {
    s.basis += ": one of the two groups is empty";
    return s;
  }
  s.mean_large = g.large, s.mean_small = g.small;
  s.index = 2.0 * (s.mean_large - s.mean_small) / (s.mean_large + s.mean_small);
  s.valid = true;
  return s;
}

}  // namespace

SegregationIndex vertical_segregation(const Grains& grains) {
  std::vector<double> c(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) c[i] = grains[i].x.z();
  return segregation_of(grains, c);
}

std::vector<double> axis_distances(const Grains& grains, const Vec3& point, const Vec3& direction) {
  const Vec3 u = direction.normalized();
  std::vector<double> c(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) {
    const Vec3 v = grains[i].x - point, w = v - v.dot(u) * u;
    c[i] = std::hypot(std::hypot(w.x(), w.y()), w.z());  // along y: exactly hypot(x, z), the drum's distance
  }
  return c;
}

SegregationIndex radial_segregation(const Grains& grains, const Vec3& point, const Vec3& direction) {
  return segregation_of(grains, axis_distances(grains, point, direction));
}

DrumMeasures drum_measures(const Grains& grains, int dimension, const Container& container) {
  DrumMeasures m;
  if (grains.empty()) return m;
  std::vector<double> radii;
  double w_sum = 0.0;
  for (const Grain& g : grains) {
    radii.push_back(g.r);
    const double w = dimension == 3 ? g.r * g.r * g.r : g.r * g.r;
    m.com_x += w * g.x.x(), m.com_z += w * g.x.z(), w_sum += w;
  }
  m.com_x /= w_sum, m.com_z /= w_sum;
  std::nth_element(radii.begin(), radii.begin() + radii.size() / 2, radii.end());
  m.split_radius = radii[radii.size() / 2];
  std::vector<char> small(grains.size()), large(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) small[i] = grains[i].r <= m.split_radius, large[i] = !small[i];
  const GroupMeans axis = group_means(axis_distances(grains, Vec3(0, 0, container.radius), Vec3::UnitY()), large, small);
  const GroupMeans core = group_means(axis_distances(grains, Vec3(m.com_x, 0, m.com_z), Vec3::UnitY()), large, small);
  m.axis_small = axis.small, m.axis_large = axis.large, m.core_small = core.small, m.core_large = core.large;
  m.segregation_index = axis.n_small && axis.n_large ? (m.axis_large - m.axis_small) / container.radius : 0.0;

  const double half = 0.6 * container.radius;
  const HeightMap h = height_map(grains, 2, -half, half, 0.0, 0.0, 2.0 * max_radius(grains), 1 << 20);
  LineFit fit;
  const double wx = 2.0 * half / h.nx;
  for (int k = 0; k < h.nx; ++k)
    if (h.top[k] > 0.0) fit.add(-half + (k + 0.5) * wx, h.top[k]);
  if (fit.ok()) {
    m.surface_valid = true;
    m.surface_angle_deg = std::atan(fit.slope()) * 180.0 / kPi;
  }
  return m;
}

std::vector<double> surface_depth(const Grains& grains, int dimension) {
  std::vector<double> depth(grains.size(), 0.0);
  if (grains.empty()) return depth;
  double x0 = std::numeric_limits<double>::max(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const Grain& g : grains) {
    x0 = std::min(x0, g.x.x()), x1 = std::max(x1, g.x.x());
    y0 = std::min(y0, g.x.y()), y1 = std::max(y1, g.x.y());
  }
  const double d = 2.0 * max_radius(grains);
  const HeightMap h = height_map(grains, dimension, x0, x1 + 1e-9 * d, y0, y1 + 1e-9 * d, d, 1 << 20);
  const double wx = (h.ex.back() - h.ex.front()) / h.nx;
  const double wy = dimension == 3 ? (h.ey.back() - h.ey.front()) / h.ny : 1.0;
  for (std::size_t k = 0; k < grains.size(); ++k) {
    const Grain& g = grains[k];
    const int i = std::clamp(static_cast<int>((g.x.x() - x0) / wx), 0, h.nx - 1);
    const int j = dimension == 3 ? std::clamp(static_cast<int>((g.x.y() - y0) / wy), 0, h.ny - 1) : 0;
    depth[k] = h.top[std::size_t(j) * h.nx + i] - g.x.z();
  }
  return depth;
}

PackingMeasures measure_packing(const Grains& grains, int dimension, const Container& container,
                                const MetricsOptions& options, bool heap_source, double source_x,
                                double source_y) {
  PackingMeasures m;
  m.options = options;
  m.n_grains = static_cast<std::int64_t>(grains.size());
  m.heap_source = heap_source, m.source_x = source_x, m.source_y = source_y;
  if (grains.empty()) {
    m.bulk.note = "no grains";
    return m;
  }
  double sum_d = 0.0, sum_z = 0.0;
  for (const Grain& g : grains) {
    sum_d += 2.0 * g.r, sum_z += g.x.z();
    m.max_top = std::max(m.max_top, g.x.z() + g.r);
  }
  m.mean_diameter = sum_d / double(grains.size());
  m.largest_diameter = 2.0 * max_radius(grains);
  m.mean_centre_height = sum_z / double(grains.size());
  m.coordination = coordination_numbers(grains, dimension, container, options.contact_tol);
  double total = 0.0;
  for (int z : m.coordination) total += z;
  m.mean_coordination_all = total / double(grains.size());
  m.bulk = bulk_measures(grains, dimension, container, options, &m.coordination);
  m.rdf = radial_distribution(grains, dimension, container, m.bulk, options);
  if (heap_source)
    m.heap = heap_measures(grains, dimension, source_x, source_y,
                           dimension == 2 || container.kind == ContainerKind::HeleShaw);
  if (heap_source) m.stratification = stratification_measures(grains, dimension, m.heap, source_x, source_y);
  std::vector<double> x(grains.size());
  for (std::size_t i = 0; i < grains.size(); ++i) x[i] = grains[i].x.x();
  m.profile_x = surface_profile(grains, x);
  m.segregation = vertical_segregation(grains);
  m.height_profile = height_profile(grains, dimension, m.bulk, options.margin_diameters * m.largest_diameter,
                                    m.largest_diameter);
  return m;
}

HeightProfile height_profile(const Grains& grains, int dimension, const BulkMeasures& bulk, double margin,
                             double thickness) {
  HeightProfile p;
  if (!bulk.valid || !bulk.slab || !(thickness > 0.0)) return p;
  const double area = (bulk.window.hi.x() - bulk.window.lo.x()) *
                      (dimension == 3 ? bulk.window.hi.y() - bulk.window.lo.y() : 1.0);
  const auto slabs = static_cast<std::size_t>(std::floor((bulk.window.hi.z() + margin) / thickness));
  if (slabs == 0) return p;
  std::vector<double> solid(slabs, 0.0);
  for (const Grain& g : grains) {
    const double lo = std::max(0.0, std::floor((g.x.z() - g.r) / thickness));
    for (auto k = static_cast<std::size_t>(lo); k < slabs && k * thickness < g.x.z() + g.r; ++k)
      solid[k] += grain_volume_in_slab(g, dimension, k * thickness, (k + 1) * thickness);
  }
  p.thickness = thickness;
  for (std::size_t k = 0; k < slabs; ++k) {
    p.z_mid.push_back((k + 0.5) * thickness);
    p.packing_fraction.push_back(solid[k] / (area * thickness));
  }
  return p;
}

}  // namespace btr
