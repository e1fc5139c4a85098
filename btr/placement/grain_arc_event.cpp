// The events of a roll among fixed grains (grain_arc_event.h).
#include "btr/placement/grain_arc_event.h"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "btr/placement/descent.h"
#include "btr/placement/neighbour_grid.h"

namespace btr {
namespace {

// Events closer than this (radians) are simultaneous.
constexpr double kTieT = 1e-13;

// (cos t, sin t) of the part boxes' split (no result depends on its last bits: the parts only gather candidates).
ArcDirection split_direction(double t) {
  ArcDirection d;
  screen_cos_sin(t, d.c, d.s);
  return d;
}

// Does the arc end by t > 0 (std::min(arc.t_end, t) is t_end)? If not, split is t's direction (split_direction).
// A pending end is compared in pseudo-angle where the two lie more than a margin apart, as roots are with the
// event (the pseudo-angle grows no faster than the angle); its angle is taken otherwise.
bool ends_by(const CircleArc& arc, double t, ArcDirection& split) {
  if (arc.end_pending && t >= kTwoPi) return true;  // t_end <= 2 pi
  if (arc.end_pending && has_root_screen(t)) {
    split = split_direction(t);
    const double end = arc.end_key, at = pseudo_angle(split.c, split.s);
    if (end < at - kScreenMargin) return true;
    if (end > at + kScreenMargin) return false;
  }
  if (!(t < arc.end_angle())) return true;
  split = split_direction(t);
  return false;
}

// The arc from t0 to t1 (directions d0 and d1, known), rotated to start at t0: its end relative to that.
CircleArc part_between(const CircleArc& arc, double t0, ArcDirection d0, double t1, ArcDirection d1) {
  CircleArc part = arc;
  part.u = d0.c * arc.u + d0.s * arc.v;
  part.v = d0.c * arc.v - d0.s * arc.u;
  part.set_end(t1 - t0, {d1.c * d0.c + d1.s * d0.s, d1.s * d0.c - d1.c * d0.s});
  return part;
}

}  // namespace

void offer_grains_on_arc(const NeighbourGrid& grid, double r, double r_max, const Contacts& supports,
                         const CircleArc& arc, const Vec3& start, Event& ev) {
  // root_screen of the event so far, for the parameter screen_t (a pending event's: pending_screen)
  double screen_t = -1.0, screen = ev.t_pending ? ev.pending_screen() : 5.0;
  auto offer_sphere = [&](const Obstacle& o) {
    const Vec3 w = arc.C - o.c;
    const double R2 = o.R * o.R;
    const double K = w.squaredNorm() + arc.rho * arc.rho;
    const double a = 2.0 * arc.rho * w.dot(arc.u), b = 2.0 * arc.rho * w.dot(arc.v);
    // The whole circle passes outside: min D = K - sqrt(a^2 + b^2) > R^2 (squared, without the root).
    const double excess = K - R2 * (1.0 + 1e-9);
    if (excess > 0.0 && excess * excess > a * a + b * b) return;
    if (supports.has(o.key)) return;
    // Distance squared D(t) = K + a cos t + b sin t; the grain enters where D falls through R^2.
    // Touching at the start: an event now if approaching; otherwise skip the tangency itself
    // (round-off puts a root there) and look for the next crossing.
    const bool touching = K + a - R2 <= 1e-9 * R2;  // a start a hair inside included, as for walls
    if (touching && b < -2.0 * kApproach * arc.rho * o.R) {
      ev.offer(0.0, o, kTieT, kArcStart);
      return;
    }
    if (!ev.t_pending && screen_t != ev.t) screen_t = ev.t, screen = root_screen_after(ev.t, ev.direction, kTieT);
    // first_rising_root(-a, -b, K - R2, t_min, ev.t + kTieT, screen), its angle taken only when needed.
    TrigRoot root;
    if (!rising_root(-a, -b, K - R2, root)) return;
    const double key = pseudo_angle(root.x, root.y);
    if (screen < 5.0 && key > screen) return;
    const ArcDirection direction{root.x / root.A2, root.y / root.A2};
    const double t_min = touching ? kSkipTangency : 0.0;
    // More than a margin before the event (screen less twice that) and after t_min in pseudo-angle: as the
    // pseudo-angle grows no faster than the angle (and from 0 at t = 0), the root lies in (t_min, ev.t - kTieT),
    // unwrapped, so an offer would make it the event. It is, its angle left to Event::resolve (the same atan2);
    // only roots within the margins, where round-off could order them either way, take atan2 here.
    if (screen < 5.0 && key < screen - 2.0 * kScreenMargin && key > t_min + kScreenMargin) {
      ev.offer_pending(o, root.x, root.y, key, direction);
      screen = ev.pending_screen();
      return;
    }
    ev.resolve();
    const double t = angle_after(root.x, root.y, t_min);
    if (t <= ev.t + kTieT) ev.offer(t, o, kTieT, direction);
  };
  // In two parts: first the grains near the arc's first stretch (1.5 radii of travel), where a rolling grain
  // usually meets the next one; only if no event is found there, those near the rest of the arc up to the
  // event so far. An obstacle met before the event found lies near the part of the arc before it, so the
  // first visit alone suffices when the event is in its part.
  const Vec3 reach = Vec3::Constant(r + r_max);
  // The grains near a part of the arc (from_start: the part that starts where the arc does).
  auto visit_part = [&](const CircleArc& part, bool from_start) {
    Vec3 plo, phi;
    part.bounds(plo, phi);
    if (from_start) plo = plo.cwiseMin(start), phi = phi.cwiseMax(start);  // the start exactly, whatever round-off
    // The box and r copied into the visitor: read from it directly at every entry (offer_sphere's stores
    // may alias them as far as the compiler knows, so they are reloaded, but not through a pointer).
    grid.visit_box(plo - reach, phi + reach, [plo, phi, r, &offer_sphere](std::int32_t i, const Vec3& c, double radius, int image) {
      const double R = r + radius;
      if ((c - c.cwiseMax(plo).cwiseMin(phi)).squaredNorm() > R * R) return;  // too far from the part's box
      Obstacle o;
      o.kind = Obstacle::Kind::Sphere;
      o.key = sphere_key(i, image);
      o.c = c;
      o.R = R;
      offer_sphere(o);
    });
  };
  const double first = 1.5 * r / arc.rho;
  ArcDirection split;
  if (ends_by(arc, first, split)) {
    visit_part(arc, true);
    return;
  }
  CircleArc part = arc;
  part.set_end(first, split);
  visit_part(part, true);
  // A pending event clearly before the split (first <= 1.5 rad here) needs no angle.
  if (ev.t_pending && pseudo_angle(split.c, split.s) - kScreenMargin <= screen) ev.resolve();
  if (!ev.t_pending && ev.t > first)
    visit_part(part_between(arc, first, split, ev.t, direction_of(ev.t, ev.direction)), false);
}

// A support lifts off where its load changes sign: gravity's part normal to the path is then parallel to the
// other support's normal, det(z, T(t), N_other(t)) = 0.
void offer_lift_offs(const Contacts& supports, const CircleArc& arc, Event& ev) {
  // z . (p x q) written out: Eigen's product keeps the terms with z's zeros (0 * x is not 0 for every
  // double), the same value at several times the cost.
  auto vertical_cross = [](const Vec3& p, const Vec3& q) { return p.x() * q.y() - p.y() * q.x(); };
  const Vec3 z = Vec3::UnitZ();
  // A pending event's t is taken only if a root passes its screen (most roots do not).
  auto screen_of = [&ev] { return ev.t_pending ? ev.pending_screen() : root_screen_after(ev.t, ev.direction, 0.0); };
  double lift_screen_t = ev.t, lift_screen = screen_of();  // again when a lift-off moves ev.t
  for (int k = 0; k < 2; ++k) {
    const Obstacle& other = supports.item[1 - k];
    double a, b, c;
    if (other.kind == Obstacle::Kind::Sphere) {
      const Vec3 w = arc.C - other.c;
      a = vertical_cross(arc.v, w);
      b = -vertical_cross(arc.u, w);
      c = arc.rho * vertical_cross(arc.u, arc.v);
    } else {
      a = vertical_cross(arc.v, other.c);
      b = -vertical_cross(arc.u, other.c);
      c = 0.0;
    }
    if (!ev.t_pending && lift_screen_t != ev.t) lift_screen_t = ev.t, lift_screen = screen_of();
    double roots[2];
    ArcDirection directions[2];
    const double t_max = ev.t_pending ? std::numeric_limits<double>::infinity() : ev.t;
    const int n = trig_roots(a, b, c, kTieT, t_max, roots, lift_screen, directions);
    for (int m = 0; m < n; ++m) {
      ev.resolve();
      if (roots[m] > ev.t) break;  // trig_roots' own test had t been known (the roots ascend)
      // Load of support k just after the root: 1e-7 past it, or half way to the arc's end if that is nearer (not
      // when the event, at most the end, lies far beyond: the end's angle is then not needed).
      const double past = roots[m] + 1e-7;
      const double t = ev.t - roots[m] > 1e-6 ? past : std::min(past, 0.5 * (roots[m] + arc.end_angle()));
      const Vec3 P = arc.at(t), T = arc.tangent(t);
      const Vec3 g_perp = z - z.dot(T) * T;
      if (unloads(g_perp, supports.item[k].normal(P), other.normal(P)) && roots[m] < ev.t - kTieT) {
        ev.t = roots[m];
        ev.direction = directions[m];
        ev.hits.n = 0;
        ev.lift_off = k;
        break;
      }
    }
  }
}

Event first_grain_event(const NeighbourGrid& grid, double r, double r_max, const Contacts& supports,
                        const CircleArc& arc) {
  Event ev(arc);
  offer_grains_on_arc(grid, r, r_max, supports, arc, arc.at(0.0), ev);
  if (supports.n == 2) offer_lift_offs(supports, arc, ev);
  ev.resolve();
  return ev;
}

}  // namespace btr

namespace btr {

double first_grain_on_segment(const NeighbourGrid& grid, double r, double r_max, const Vec3& x0, const Vec3& g,
                              double s_max, const std::int64_t* skip, int n_skip, std::vector<Obstacle>& hits) {
  hits.clear();
  double s_best = s_max;
  const double tie = 1e-13 * r;
  auto skipped = [&](std::int64_t key) {
    for (int k = 0; k < n_skip; ++k)
      if (skip[k] == key) return true;
    return false;
  };
  // In chunks of a few radii, nearest first: a grain met within the chunks visited ends the search (one
  // met earlier touches the segment before that point, so near a chunk already visited).
  const double chunk = 4.0 * r;
  const Vec3 reach = Vec3::Constant(r + r_max);
  for (double s0 = 0.0; s0 < s_best; s0 += chunk) {
    const double s1 = std::min(s_best, s0 + chunk);
    const Vec3 a = x0 + s0 * g, b = x0 + s1 * g;
    const Vec3 lo = a.cwiseMin(b), hi = a.cwiseMax(b);
    grid.visit_box(lo - reach, hi + reach, [&](std::int32_t i, const Vec3& c, double radius, int image) {
      const double R = r + radius;
      if ((c - c.cwiseMax(lo).cwiseMin(hi)).squaredNorm() > R * R) return;
      // |x0 + s g - c|^2 = R^2: s^2 + 2 p s + q = 0
      const Vec3 w = x0 - c;
      const double p = w.dot(g), q = w.squaredNorm() - R * R;
      double s;
      if (std::abs(q) <= 1e-9 * R * R) {
        if (!(p < -kApproach * R)) return;  // touching and tangent or moving away
        s = 0.0;
      } else {
        const double disc = p * p - q;
        if (q < 0.0 || disc <= 0.0 || p >= 0.0) return;  // inside (round-off far exceeded), missed, or behind
        s = -p - std::sqrt(disc);
        if (s > s_best + tie) return;
      }
      const std::int64_t key = sphere_key(i, image);
      if (skipped(key)) return;
      Obstacle o;
      o.kind = Obstacle::Kind::Sphere;
      o.key = key;
      o.c = c;
      o.R = R;
      if (s < s_best - tie) s_best = s, hits.clear();
      for (const Obstacle& h : hits)
        if (h.key == key) return;
      hits.push_back(o);
    });
  }
  return s_best;
}

}  // namespace btr
