#pragma once
// The active contacts of a grain being placed and the first event along its path: the analytic engine's
// (btr/placement/deposition.cpp) and the mesh placement's exact moves (btr/placement/mesh_exact_moves.cpp).
#include <limits>
#include <new>
#include <type_traits>

#include "btr/placement/circle_arc.h"
#include "btr/placement/descent.h"
#include "btr/placement/obstacle.h"

namespace btr {

// Arc parameter skipped after a tangency with a contact the grain is leaving (radians).
inline constexpr double kSkipTangency = 1e-9;
// A contact touched at the start of a path is met only if the path heads into it at least this
// steeply (cosine of the angle with its normal); below it the path is tangent up to round-off.
inline constexpr double kApproach = 1e-9;

static_assert(std::is_trivially_destructible_v<Obstacle>, "Contacts never destroys its obstacles");

// At most kMaxContacts (btr/placement/descent.h); one more sets `overflow`, which the placement reports as an error.
// The items are raw storage (only the first n are ever read) and a copy copies n of them: a Contacts is
// built and copied at every event, and initialising kMaxContacts obstacles each time cost more than the
// contacts' own work.
struct Contacts {
  struct Items {
    alignas(Obstacle) unsigned char raw[kMaxContacts * sizeof(Obstacle)];
    Obstacle& operator[](int i) { return reinterpret_cast<Obstacle*>(raw)[i]; }
    const Obstacle& operator[](int i) const { return reinterpret_cast<const Obstacle*>(raw)[i]; }
  } item;
  int n = 0;
  bool overflow = false;
  Contacts() {}  // user-provided: `Contacts{}` leaves the items alone
  Contacts(const Contacts& o) : n(o.n), overflow(o.overflow) {
    for (int i = 0; i < n; ++i) new (&item[i]) Obstacle(o.item[i]);
  }
  Contacts& operator=(const Contacts& o) {
    if (this == &o) return *this;
    n = o.n;
    overflow = o.overflow;
    for (int i = 0; i < n; ++i) new (&item[i]) Obstacle(o.item[i]);
    return *this;
  }
  bool has(std::int64_t key) const {
    for (int i = 0; i < n; ++i)
      if (item[i].key == key) return true;
    return false;
  }
  void add(const Obstacle& o) {
    if (has(o.key)) return;
    if (n < kMaxContacts) new (&item[n++]) Obstacle(o);
    else overflow = true;
  }
  void add_all(const Contacts& other) {
    for (int k = 0; k < other.n; ++k) add(other.item[k]);
    overflow |= other.overflow;
  }
  void remove(int i) {
    for (int k = i; k + 1 < n; ++k) item[k] = item[k + 1];
    --n;
  }
};

// The first event found along a path: its parameter and the obstacles met there.
// A constructor rather than aggregate initialisation: `Event{t, {}, -1}` zero-filled the whole of `hits`
// (800 bytes) at every fall and roll.
struct Event {
  explicit Event(double t_end, ArcDirection end = ArcDirection::unknown()) : t(t_end), direction(end) {}
  // The arc's end, pending as long as the arc's own angle is.
  explicit Event(const CircleArc& arc) : t(arc.t_end), direction(arc.end) {
    if (arc.end_pending) t_pending = true, pending_x = arc.end_x, pending_y = arc.end_y, pending_key = arc.end_key;
  }
  double t;
  ArcDirection direction;  // on an arc, t's direction when the offer that set t knew it
  Contacts hits;
  int lift_off = -1;  // index in the active contacts of a support that unloads
  // A root taken as the new event without its angle (offer_grains_on_arc: it lies before t by far more than tol),
  // or an arc's end whose angle is pending (CircleArc::set_end_towards): t is NaN until resolve() takes it from
  // the direction (x, y) (angle_after), as an offer or the arc would have.
  bool t_pending = false;
  double pending_x = 0.0, pending_y = 0.0, pending_key = 0.0;  // pending_key: the direction's pseudo-angle
  // The root screen of a pending t (root_screen_after without the angle): a pending t's pseudo-angle is more
  // than the margin past 0, so it cannot have wrapped to 2 pi and stands for t.
  double pending_screen() const { return pending_key + kScreenMargin; }
  // The largest root an offer can take or tie with: t + tol, or while t is pending any (offer resolves t first).
  double reach(double tol) const { return t_pending ? std::numeric_limits<double>::infinity() : t + tol; }
  void offer_pending(const Obstacle& o, double x, double y, double key, ArcDirection at) {
    t = std::numeric_limits<double>::quiet_NaN();
    t_pending = true, pending_x = x, pending_y = y, pending_key = key;
    direction = at;
    hits.n = 0;
    hits.overflow = false;
    lift_off = -1;
    hits.add(o);
  }
  void resolve() {
    if (t_pending) t = angle_after(pending_x, pending_y, 0.0), t_pending = false;
  }
  void offer(double t_new, const Obstacle& o, double tol, ArcDirection at = ArcDirection::unknown()) {
    resolve();
    if (t_new < t - tol) {
      t = t_new;
      direction = at;
      hits.n = 0;
      hits.overflow = false;
      lift_off = -1;
    }
    if (t_new <= t + tol) hits.add(o);
  }
};

}  // namespace btr
