#pragma once
// A path followed in steps (the curve along a cylinder or drum wall, btr/placement/deposition.cpp; the mesh
// walker's steps, btr/placement/mesh_placement.cpp) sees a partner only where a sample lies inside it: one the path enters and leaves between two samples would be
// passed. Between two samples that are both clear, this search proves each partner clear or finds a point
// inside one. A partner's gap is 1-Lipschitz in the centre, so partner o stays clear (to `depth`) over [a, b] when
//   gap_o(P(a)) >= spread(a, b - a) - depth  or  gap_o(P(b)) >= spread(b, a - b) - depth,
// with spread(f, h) a bound on how far the centre moves from P(f) while the path's parameter (an angle, a
// fraction of a step) runs over h. Spans that cannot be cleared are split, leftmost first, down to 1e-15.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "btr/placement/obstacle.h"

namespace btr {

// The angle through which a point on a circle of radius Rc (the tube's section) turns over h moves it at
// most Rc |h|; along the axis, w = w_p +- sqrt(s) with s = R_p^2 - q^2 (q: the section's distance from the
// support's section, which changes by at most that much), so |dw| <= |ds| / sqrt(s) <= c (2 q + c) / sqrt(s).
inline double tube_path_spread(double Rc, double h, double q, double s) {
  if (!(s > 0.0)) return std::numeric_limits<double>::infinity();
  const double c = Rc * std::abs(h);
  return std::hypot(c, c * (2.0 * q + c) / std::sqrt(s));
}

namespace detail {

inline bool clear_from(const Obstacle& o, const Vec3& P, double spread, double depth) {
  const double need = spread - depth;  // the gap that keeps o clear
  if (o.kind == Obstacle::Kind::Sphere) {
    const double d = o.R + need;
    return d <= 0.0 || (P - o.c).squaredNorm() >= d * d;
  }
  return o.gap(P) >= need;
}

// clear(item, Plo, Phi, Dlo, Dhi, S): item is proven clear (to depth) over the span whose ends are Plo and Phi,
// the centre's travel from them bounded by Dlo and Dhi, and S = sag(lo, hi) (below); inside(item, P): its gap
// is below -depth. A midpoint off the path (NaN) is returned as found: the caller's own test there decides.
template <class Item, class Clear, class Inside, class At, class Spread, class Sag>
double graze_in(double lo, double hi, const Vec3& Plo, const Vec3& Phi, const std::vector<const Item*>& partners,
                Clear& clear, Inside& inside, At& at, Spread& spread, Sag& sag) {
  const double Dlo = spread(lo, hi - lo), Dhi = spread(hi, lo - hi), S = sag(lo, hi);
  std::vector<const Item*> open;
  for (const Item* o : partners)
    if (!clear(*o, Plo, Phi, Dlo, Dhi, S)) open.push_back(o);
  if (open.empty() || std::abs(hi - lo) <= 1e-15 * std::max(1.0, std::abs(lo))) return std::nan("");
  const double m = 0.5 * (lo + hi);
  const Vec3 Pm = at(m);
  if (!Pm.allFinite()) return m;
  const double left = graze_in(lo, m, Plo, Pm, open, clear, inside, at, spread, sag);
  if (!std::isnan(left)) return left;
  for (const Item* o : open)
    if (inside(*o, Pm)) return m;
  return graze_in(m, hi, Pm, Phi, open, clear, inside, at, spread, sag);
}

}  // namespace detail

// Between samples a and b of the path (both clear), the leftmost angle found where a partner is entered
// deeper than `depth`, or NaN when every partner is proven clear to that depth (a shallower graze is a
// tangency, as for the arcs). at(f) is the centre at angle f (NaN coordinates off the path), spread(f, h)
// bounds its travel from there over h (tube_path_spread).
// touching: partners whose gap at a is below it are left to the step's test at b. The first step of a walk
// passes a small positive value: its start is no checked sample, and a grain it starts on (released by the
// descent, or crept a hair into by round-off) is one the path leaves; later steps pass -infinity.
template <class At, class Spread>
double first_graze(double a, double b, const Vec3& Pa, const Vec3& Pb, const std::vector<Obstacle>& partners,
                   double depth, double touching, At at, Spread spread) {
  const double Da = spread(a, b - a), Db = spread(b, a - b);
  const bool skip = touching > -std::numeric_limits<double>::infinity();
  std::vector<const Obstacle*> open;
  for (const Obstacle& o : partners)
    if (!detail::clear_from(o, Pa, Da, depth) && !detail::clear_from(o, Pb, Db, depth) && !(skip && o.gap(Pa) < touching))
      open.push_back(&o);
  if (open.empty()) return std::nan("");
  auto clear = [depth](const Obstacle& o, const Vec3& Plo, const Vec3& Phi, double Dlo, double Dhi, double) {
    return detail::clear_from(o, Plo, Dlo, depth) || detail::clear_from(o, Phi, Dhi, depth);
  };
  auto inside = [depth](const Obstacle& o, const Vec3& P) { return o.gap(P) < -depth; };
  auto no_sag = [](double, double) { return 0.0; };
  return detail::graze_in(a, b, Pa, Pb, open, clear, inside, at, spread, no_sag);
}

// The same search for partners of any kind, each with its gap: gap(item, P), 1-Lipschitz in P (the mesh
// walker's grains and triangles, btr/placement/mesh_placement.cpp), with a second test: sag(lo, hi) bounds
// how far a partner's gap can fall below the lower of its two ends' over [lo, hi] (a gap whose second
// derivative along the path is at least -M falls at most M (hi - lo)^2 / 8 below the chord of its ends), which
// clears a partner nearly level along the path (one the travel bound alone would clear only in many short
// spans). Partners whose gap at a or at b is below `touching` are left out: the path starts or ends on them.
template <class Item, class Gap, class At, class Spread, class Sag>
double first_graze_of(double a, double b, const Vec3& Pa, const Vec3& Pb, const std::vector<Item>& partners, Gap gap,
                      double depth, double touching, At at, Spread spread, Sag sag) {
  auto clear = [&](const Item& o, const Vec3& Plo, const Vec3& Phi, double Dlo, double Dhi, double S) {
    const double glo = gap(o, Plo), ghi = gap(o, Phi);
    return glo >= Dlo - depth || ghi >= Dhi - depth || std::min(glo, ghi) >= S - depth;
  };
  const double Da = spread(a, b - a), Db = spread(b, a - b);
  double S = std::nan("");  // sag(a, b), taken only for a partner the travel bound leaves open
  std::vector<const Item*> open;
  for (const Item& o : partners) {
    const double ga = gap(o, Pa), gb = gap(o, Pb);
    if (ga < touching || gb < touching || ga >= Da - depth || gb >= Db - depth) continue;
    if (std::isnan(S)) S = sag(a, b);
    if (std::min(ga, gb) < S - depth) open.push_back(&o);
  }
  if (open.empty()) return std::nan("");
  auto inside = [&](const Item& o, const Vec3& P) { return gap(o, P) < -depth; };
  return detail::graze_in(a, b, Pa, Pb, open, clear, inside, at, spread, sag);
}

}  // namespace btr
