#include "btr/placement/mesh_index.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "btr/placement/mesh_line_reach.h"

namespace btr {

MeshIndex::MeshIndex(const TriangleMesh& mesh, double cell) : mesh_(mesh) {
  const auto& V = mesh.vertices;
  const std::size_t n = mesh.triangles.size();
  box_lo_.resize(n), box_hi_.resize(n), normal_.resize(n);
  std::map<std::pair<int, int>, int> edge_use;
  for (std::size_t t = 0; t < n; ++t) {
    const auto& f = mesh.triangles[t];
    box_lo_[t] = V[f[0]].cwiseMin(V[f[1]]).cwiseMin(V[f[2]]);
    box_hi_[t] = V[f[0]].cwiseMax(V[f[1]]).cwiseMax(V[f[2]]);
    normal_[t] = (V[f[1]] - V[f[0]]).cross(V[f[2]] - V[f[0]]).normalized();
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      ++edge_use[{std::min(a, b), std::max(a, b)}];
    }
  }
  double largest = 0.0;  // the largest file coordinate, scaled
  for (const Vec3& v : V) largest = std::max(largest, (v - mesh.shift).cwiseAbs().maxCoeff());
  vertex_roundoff_ = 0x1p-24 * largest;
  for (const auto& [e, uses] : edge_use)
    if (uses == 1) rim_.push_back({e.first, e.second});
  // Columns about the nominal width, at most 512 along each side (a large mesh with small grains).
  const double lx = mesh.hi.x() - mesh.lo.x(), ly = mesh.hi.y() - mesh.lo.y();
  w_ = std::max({cell, lx / 512.0, ly / 512.0});
  x0_ = mesh.lo.x(), y0_ = mesh.lo.y();
  nx_ = std::max(1L, static_cast<long>(std::ceil(lx / w_)));
  ny_ = std::max(1L, static_cast<long>(std::ceil(ly / w_)));
  columns_.resize(static_cast<std::size_t>(nx_ * ny_));
  // A column holds the triangles whose shadow on the x-y plane meets it (a slanted triangle's bounding box
  // covers far more columns than the triangle does), by separating axes: the column's sides, and the
  // normals of the shadow's sides, with a margin far above round-off.
  for (std::size_t t = 0; t < n; ++t) {
    const auto& f = mesh.triangles[t];
    const double eps = 1e-9 * w_;
    auto meets = [&](long i, long j) {
      const double cx0 = x0_ + static_cast<double>(i) * w_ - eps, cx1 = x0_ + static_cast<double>(i + 1) * w_ + eps;
      const double cy0 = y0_ + static_cast<double>(j) * w_ - eps, cy1 = y0_ + static_cast<double>(j + 1) * w_ + eps;
      for (int k = 0; k < 3; ++k) {
        const Vec3 &a = V[f[k]], &b = V[f[(k + 1) % 3]];
        const double nx = b.y() - a.y(), ny = a.x() - b.x();
        if (nx == 0.0 && ny == 0.0) continue;
        double tmin = std::numeric_limits<double>::infinity(), tmax = -tmin;
        for (int m = 0; m < 3; ++m) {
          const double p = nx * V[f[m]].x() + ny * V[f[m]].y();
          tmin = std::min(tmin, p), tmax = std::max(tmax, p);
        }
        const double c[4] = {nx * cx0 + ny * cy0, nx * cx1 + ny * cy0, nx * cx0 + ny * cy1, nx * cx1 + ny * cy1};
        const double cmin = std::min({c[0], c[1], c[2], c[3]}), cmax = std::max({c[0], c[1], c[2], c[3]});
        const double slack = 1e-9 * (std::abs(tmin) + std::abs(tmax) + std::abs(cmin) + std::abs(cmax));
        if (cmax < tmin - slack || cmin > tmax + slack) return false;
      }
      return true;
    };
    for (long j = iy(box_lo_[t].y()); j <= iy(box_hi_[t].y()); ++j)
      for (long i = ix(box_lo_[t].x()); i <= ix(box_hi_[t].x()); ++i)
        if (meets(i, j)) columns_[static_cast<std::size_t>(i + nx_ * j)].push_back(static_cast<int>(t));
  }
  rim_columns_.resize(columns_.size());
  for (std::size_t k = 0; k < rim_.size(); ++k) {
    const Vec3 &a = V[rim_[k][0]], &b = V[rim_[k][1]];
    for (long j = iy(std::min(a.y(), b.y())); j <= iy(std::max(a.y(), b.y())); ++j)
      for (long i = ix(std::min(a.x(), b.x())); i <= ix(std::max(a.x(), b.x())); ++i)
        rim_columns_[static_cast<std::size_t>(i + nx_ * j)].push_back(static_cast<int>(k));
  }
  stamp_.assign(n, 0u);
  // The clearance cells are two columns wide: a fill costs a collect over the cap's box, and the bound it
  // gives (the cell centre's distance less the point's offset, up to 1.7 w_) still covers a grain's arc.
  fw_ = 2.0 * w_;
  fnx_ = std::max(1L, static_cast<long>(std::ceil(lx / fw_)));
  fny_ = std::max(1L, static_cast<long>(std::ceil(ly / fw_)));
  fnz_ = std::max(1L, static_cast<long>(std::ceil((mesh.hi.z() - mesh.lo.z()) / fw_)));
  cap_ = 5.0 * w_;
  if (static_cast<double>(fnx_) * static_cast<double>(fny_) * static_cast<double>(fnz_) <= 1 << 24)
    field_.assign(static_cast<std::size_t>(fnx_ * fny_ * fnz_), std::numeric_limits<float>::quiet_NaN());
}

double MeshIndex::clearance(const Vec3& x) const {
  const Vec3 outside = (mesh_.lo - x).cwiseMax(x - mesh_.hi).cwiseMax(0.0);
  if (outside.squaredNorm() > 0.0) return outside.norm();
  if (field_.empty()) return 0.0;
  auto cell_of = [&](double v, double v0, long n) { return std::clamp(static_cast<long>(std::floor((v - v0) / fw_)), 0L, n - 1); };
  const long i = cell_of(x.x(), x0_, fnx_), j = cell_of(x.y(), y0_, fny_), k = cell_of(x.z(), mesh_.lo.z(), fnz_);
  const Vec3 centre(x0_ + (static_cast<double>(i) + 0.5) * fw_, y0_ + (static_cast<double>(j) + 0.5) * fw_,
                    mesh_.lo.z() + (static_cast<double>(k) + 0.5) * fw_);
  float& cell = field_[static_cast<std::size_t>(i + fnx_ * (j + fny_ * k))];
  if (std::isnan(cell)) {
    std::vector<int> near;
    collect(centre - Vec3::Constant(cap_), centre + Vec3::Constant(cap_), near);
    double d = cap_;
    for (int t : near)
      if (distance_bound(t, centre) < d * (1.0 + 1e-9)) d = std::min(d, distance(t, centre));
    float f = static_cast<float>(d);
    if (static_cast<double>(f) > d) f = std::nextafter(f, 0.0f);
    cell = f;
  }
  return std::max(0.0, static_cast<double>(cell) - (x - centre).norm());
}

long MeshIndex::ix(double x) const { return std::clamp(static_cast<long>(std::floor((x - x0_) / w_)), 0L, nx_ - 1); }
long MeshIndex::iy(double y) const { return std::clamp(static_cast<long>(std::floor((y - y0_) / w_)), 0L, ny_ - 1); }

const std::vector<int>& MeshIndex::column(double x, double y) const {
  return columns_[static_cast<std::size_t>(ix(x) + nx_ * iy(y))];
}

// Ericson, Real-Time Collision Detection, 5.1.5: by the Voronoi regions of the vertices, edges and face.
Vec3 MeshIndex::closest(int t, const Vec3& p) const {
  const auto& f = mesh_.triangles[static_cast<std::size_t>(t)];
  const Vec3& a = mesh_.vertices[f[0]];
  const Vec3& b = mesh_.vertices[f[1]];
  const Vec3& c = mesh_.vertices[f[2]];
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

double MeshIndex::distance_bound(int t, const Vec3& x) const {
  const std::size_t i = static_cast<std::size_t>(t);
  const double plane = std::abs(normal_[i].dot(x - mesh_.vertices[mesh_.triangles[i][0]]));
  const double box = (x - x.cwiseMax(box_lo_[i]).cwiseMin(box_hi_[i])).norm();
  return std::isnan(plane) ? box : std::max(plane, box);
}

void MeshIndex::collect(const Vec3& lo, const Vec3& hi, std::vector<int>& out) const {
  if (hi.x() < mesh_.lo.x() || lo.x() > mesh_.hi.x() || hi.y() < mesh_.lo.y() || lo.y() > mesh_.hi.y()) return;
  if (++visit_ == 0) std::fill(stamp_.begin(), stamp_.end(), 0u), visit_ = 1;
  const std::size_t first = out.size();
  for (long j = iy(lo.y()); j <= iy(hi.y()); ++j)
    for (long i = ix(lo.x()); i <= ix(hi.x()); ++i)
      for (int t : columns_[static_cast<std::size_t>(i + nx_ * j)]) {
        if (stamp_[static_cast<std::size_t>(t)] == visit_) continue;
        stamp_[static_cast<std::size_t>(t)] = visit_;
        const Vec3& bl = box_lo_[static_cast<std::size_t>(t)];
        const Vec3& bh = box_hi_[static_cast<std::size_t>(t)];
        if ((bl.array() <= hi.array()).all() && (bh.array() >= lo.array()).all()) out.push_back(t);
      }
  std::sort(out.begin() + static_cast<long>(first), out.end());
}

double MeshIndex::fall_contact(int t, const Vec3& x, double r, double z_floor) const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Vec3& bl = box_lo_[static_cast<std::size_t>(t)];
  const Vec3& bh = box_hi_[static_cast<std::size_t>(t)];
  if (x.x() < bl.x() - r || x.x() > bh.x() + r || x.y() < bl.y() - r || x.y() > bh.y() + r) return nan;
  if (bl.z() - r > x.z()) return nan;
  const double z0 = x.z();
  const double lo = std::min(bl.z() - 2.0 * r, z0);  // t lies above bl.z - r
  const Vec3& v0 = mesh_.vertices[mesh_.triangles[static_cast<std::size_t>(t)][0]];
  const Vec3& n = normal(t);
  {
    // Within r of the triangle is within r of its plane; the distance from the plane is linear along the
    // line, so a line whose ends at lo and z0 both keep more than r from it on one side never comes within r.
    const double h_hi = n.dot(x - v0), h_lo = h_hi + n.z() * (lo - z0);
    if ((h_hi > r && h_lo > r) || (h_hi < -r && h_lo < -r)) return nan;
  }
  if (std::isfinite(z_floor)) {
    // Within r of the triangle is within r of its plane: at most r / |n_z| above where the line crosses it.
    if (std::abs(n.z()) > 1e-3) {
      const double z_plane = v0.z() - (n.x() * (x.x() - v0.x()) + n.y() * (x.y() - v0.y())) / n.z();
      if (z_plane + r / std::abs(n.z()) + 1e-9 * r < z_floor) return nan;
    }
  }
  // In closed form: the heights where the line is within r of t, and within r (1 - 1e-10): one that comes
  // no nearer only grazes it (a grain sliding down a vertical wall), no contact.
  const auto& f = mesh_.triangles[static_cast<std::size_t>(t)];
  const Vec3 &va = mesh_.vertices[f[0]], &vb = mesh_.vertices[f[1]], &vc = mesh_.vertices[f[2]];
  if (line_within(va, vb, vc, n, x, r * (1.0 - 1e-10)).empty()) return nan;
  const HeightInterval in = line_within(va, vb, vc, n, x, r);
  if (in.lo > -1e-12 * r) return nan;  // within r only from the start up: moving away
  if (in.hi < 0.0) return z0 + in.hi;  // below the start: its top is the first contact
  // Touching at the start: a contact if the distance falls below it (the old search, for this rare case).
  return touching_fall(t, x, r, lo);
}

// The distance along the line is convex in z: its minimum by golden section on [lo, x.z]; touching at x, the
// grain moves into t if that minimum lies below.
double MeshIndex::touching_fall(int t, const Vec3& x, double r, double lo) const {
  auto f = [&](double z) { return distance(t, Vec3(x.x(), x.y(), z)); };
  const double z0 = x.z();
  double hi = z0;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = hi - g * (hi - lo), b = lo + g * (hi - lo), fa = f(a), fb = f(b);
  for (int it = 0; it < 120 && hi - lo > 1e-15 * r; ++it) {
    if (fa < fb) hi = b, b = a, fb = fa, a = hi - g * (hi - lo), fa = f(a);
    else lo = a, a = b, fa = fb, b = lo + g * (hi - lo), fb = f(b);
  }
  const double z_min = 0.5 * (lo + hi);
  if (z_min >= z0 - 1e-12 * r) return std::numeric_limits<double>::quiet_NaN();
  return z0;
}

int MeshIndex::crossings_below(double x, double y, double z) const {
  // A fixed irrational nudge of the line keeps it off shared edges and vertices, so every crossing
  // counts once (a line through an edge would otherwise meet both triangles or neither).
  const double scale = std::max(mesh_.hi.x() - mesh_.lo.x(), mesh_.hi.y() - mesh_.lo.y());
  const double px = x + 0.7548776662466927e-9 * scale, py = y + 0.5698402909980532e-9 * scale;
  int count = 0;
  const auto& V = mesh_.vertices;
  for (int t : column(px, py)) {
    const auto& f = mesh_.triangles[static_cast<std::size_t>(t)];
    const Vec3 &a = V[f[0]], &b = V[f[1]], &c = V[f[2]];
    auto orient = [&](const Vec3& p, const Vec3& q) { return (q.x() - p.x()) * (py - p.y()) - (q.y() - p.y()) * (px - p.x()); };
    const double o1 = orient(a, b), o2 = orient(b, c), o3 = orient(c, a);
    const bool inside = (o1 > 0 && o2 > 0 && o3 > 0) || (o1 < 0 && o2 < 0 && o3 < 0);
    if (!inside) continue;
    const Vec3 n = (b - a).cross(c - a);
    if (n.z() == 0.0) continue;
    const double zc = a.z() - (n.x() * (px - a.x()) + n.y() * (py - a.y())) / n.z();
    if (zc < z) ++count;
  }
  return count;
}

// The first rim edge (in index order) within r of (x, y) horizontally, or -1. A rim point within r lies in
// a column of the box (x -+ r, y -+ r), and its edge is held by every column its x-y box meets.
int MeshIndex::rim_within(double x, double y, double r) const {
  const auto& V = mesh_.vertices;
  int first = -1;
  for (long j = iy(y - r); j <= iy(y + r); ++j)
    for (long i = ix(x - r); i <= ix(x + r); ++i)
      for (int k : rim_columns_[static_cast<std::size_t>(i + nx_ * j)]) {
        if (first >= 0 && k >= first) continue;
        const Vec3 &a = V[rim_[static_cast<std::size_t>(k)][0]], &b = V[rim_[static_cast<std::size_t>(k)][1]];
        const double ex = b.x() - a.x(), ey = b.y() - a.y(), len2 = ex * ex + ey * ey;
        const double s = len2 > 0.0 ? std::clamp(((x - a.x()) * ex + (y - a.y()) * ey) / len2, 0.0, 1.0) : 0.0;
        const double dx = x - a.x() - s * ex, dy = y - a.y() - s * ey;
        if (dx * dx + dy * dy < r * r) first = k;
      }
  return first;
}

bool MeshIndex::in_footprint(double x, double y, double r) const {
  return crossings_below(x, y, std::numeric_limits<double>::infinity()) % 2 == 1 && rim_within(x, y, r) < 0;
}

std::string MeshIndex::footprint_misfit(double x, double y, double r) const {
  const int n = crossings_below(x, y, std::numeric_limits<double>::infinity());
  if (n % 2 == 0) {
    std::ostringstream why;
    why << "(x, y) = (" << x << ", " << y << ") is outside the footprint of the mesh " << mesh_.file << ": the vertical "
        << "line there crosses it " << n << " times (" << (n == 0 ? "outside its rim, or over an open outlet" : "it is closed above there")
        << "), a grain dropped there would fall past it or land outside it";
    return why.str();
  }
  const int k = rim_within(x, y, r);
  if (k >= 0) {
    const Vec3 &a = mesh_.vertices[rim_[static_cast<std::size_t>(k)][0]], &b = mesh_.vertices[rim_[static_cast<std::size_t>(k)][1]];
    std::ostringstream why;
    why << "(x, y) = (" << x << ", " << y << ") puts a grain of radius " << r << " over the open rim of the mesh "
        << mesh_.file << " (an edge of one triangle only, from (" << a.x() << ", " << a.y() << ", " << a.z() << ") to ("
        << b.x() << ", " << b.y() << ", " << b.z() << ")): it could land on the rim or outside it";
    return why.str();
  }
  return {};
}

}  // namespace btr
