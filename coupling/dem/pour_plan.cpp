// The reference pour's plan (pour_plan.h): lattice sites over the source's footprint, the lattice, the batches
// and their release steps, on top of the relaxation's plan of the lattice.
#include "coupling/dem/pour_plan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "btr/model/number_text.h"
#include "btr/placement/drops.h"
#include "coupling/dem/check_schedule.h"
#include "coupling/dem/dem_walls.h"
#include "coupling/dem/materials.h"
#include "coupling/dem/relax_plan.h"

namespace btr {

namespace {

using Site = std::pair<double, double>;

// Evenly spaced coordinates in [lo, hi]: periodic, span / n apart filling the period; otherwise from
// lo + margin to hi - margin at least `spacing` apart (one site in the middle when that range is short).
std::vector<double> grid(double lo, double hi, double spacing, double margin, bool periodic) {
  const double span = hi - lo;
  std::vector<double> out;
  if (periodic) {
    const long n = std::max(1L, static_cast<long>(std::floor(span / spacing)));
    for (long k = 0; k < n; ++k) out.push_back(lo + (k + 0.5) * span / n);
    return out;
  }
  const double usable = span - 2.0 * margin;
  const long n = usable > 0.0 ? static_cast<long>(std::floor(usable / spacing)) + 1 : 1;
  if (n == 1) return {0.5 * (lo + hi)};
  for (long k = 0; k < n; ++k) out.push_back(lo + margin + usable * k / (n - 1));
  return out;
}

// Distance from the site (x, y) to the nearest lateral wall (infinite without one).
double lateral_clearance(const std::vector<DemWall>& walls, double x, double y) {
  double c = std::numeric_limits<double>::infinity();
  for (const DemWall& w : walls)
    if (w.name != "floor") c = std::min(c, w.distance(Vec3(x, y, 1.0)));
  return c;
}

double wrap(double x, double period) { return x - period * std::floor(x / period + 0.5); }


// Uniform in [0, 1) from a 64-bit draw, as the drops draw theirs (btr/placement/drops.h).
double unit(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

}  // namespace

std::vector<Site> pour_sites(const Scene& scene, double r_max) {
  const Container& c = scene.container;
  const int dim = scene.dimension;
  const double spacing = kPourSpacing * r_max;
  const double jitter = kPourJitter * spacing;
  const double margin = 1.01 * r_max + jitter;  // a jittered grain still clears every wall
  // A mesh has no lattice of release sites written for it yet (its footprint is not a rectangle or disk).
  if (c.kind == ContainerKind::Mesh)
    refuse_scene_field(scene, "container.kind",
           "the reference pour does not support a mesh container yet (its release lattice covers boxes, "
           "cylinders and open floors); relax a BTR packing of it with `btr relax` instead");
  if (c.kind == ContainerKind::Drum)
    refuse_scene_field(scene, "container.kind",
                       "\"drum\": the reference pour has no release lattice for a drum; run it with `btr drum --engine`");
  std::vector<DemWall> walls;
  try {
    walls = dem_walls(c, dim);
  } catch (const std::runtime_error& e) {
    refuse_scene_field(scene, "container", e.what());
  }
  std::vector<Site> sites;
  auto cross = [&](const std::vector<double>& xs, const std::vector<double>& ys) {
    for (double x : xs)
      for (double y : ys) sites.emplace_back(x, y);
  };
  const std::vector<double> mid{0.0};
  switch (scene.source.kind) {
    case SourceSpec::Kind::Region: {
      const SourceSpec& s = scene.source;
      cross(grid(s.x_min - margin, s.x_max + margin, spacing, margin, false),
            dim == 3 ? grid(s.y_min - margin, s.y_max + margin, spacing, margin, false) : mid);
      break;
    }
    case SourceSpec::Kind::Point: {
      const double reach = std::max(scene.source.scatter, 1.5 * spacing);
      const long n = static_cast<long>(std::ceil(reach / spacing));
      for (long i = -n; i <= n; ++i)
        for (long j = dim == 3 ? -n : 0; j <= (dim == 3 ? n : 0); ++j)
          if (std::hypot(i * spacing, j * spacing) <= reach * (1.0 + 1e-12))
            sites.emplace_back(scene.source.x + i * spacing, dim == 3 ? scene.source.y + j * spacing : 0.0);
      break;
    }
    case SourceSpec::Kind::Rain:
    case SourceSpec::Kind::List:
      switch (c.kind) {
        case ContainerKind::Box:
        case ContainerKind::Periodic: {
          const bool per = c.kind == ContainerKind::Periodic;
          cross(grid(-0.5 * c.size_x, 0.5 * c.size_x, spacing, margin, per),
                dim == 3 ? grid(-0.5 * c.size_y, 0.5 * c.size_y, spacing, margin, per) : mid);
          break;
        }
        case ContainerKind::HeleShaw:
          cross(grid(-0.5 * c.size_x, 0.5 * c.size_x, spacing, margin, false),
                grid(-0.5 * c.gap, 0.5 * c.gap, spacing, margin, false));
          break;
        case ContainerKind::Cylinder: {
          const std::vector<double> xs = grid(-c.radius, c.radius, spacing, margin, false);
          cross(xs, xs);
          break;
        }
        default:
          refuse_scene_field(scene, "source.kind",
                 std::string("a ") + (scene.source.kind == SourceSpec::Kind::Rain ? "rain" : "list") +
                     " source is poured over the container's footprint, and an open floor has none; use a point or "
                     "region source");
      }
      break;
  }
  if (c.kind == ContainerKind::Periodic) {
    // Wrapped into the cell; a site closer than `spacing` to a kept one (a source wider than the period) is dropped.
    std::vector<Site> kept;
    for (auto [x, y] : sites) {
      x = wrap(x, c.size_x);
      if (dim == 3) y = wrap(y, c.size_y);
      bool free = true;
      for (const auto& [kx, ky] : kept) {
        const double dx = wrap(x - kx, c.size_x), dy = dim == 3 ? wrap(y - ky, c.size_y) : 0.0;
        if (std::hypot(dx, dy) < spacing * (1.0 - 1e-9)) free = false;
      }
      if (free) kept.emplace_back(x, y);
    }
    sites = std::move(kept);
  }
  // Sites that leave room for the jitter; if none does (a Hele-Shaw gap under 2 (r_max + jitter)), the sites
  // that hold a grain at all, whose jitter pour_lattice then narrows.
  for (double need : {margin, 1.01 * r_max}) {
    std::vector<Site> inside;
    for (const Site& s : sites)
      if (lateral_clearance(walls, s.first, s.second) >= need) inside.push_back(s);
    if (!inside.empty()) return inside;
  }
  refuse_scene_field(scene, "source", "no lattice site of the pour (" + g6(spacing) +
                              " m apart, 2.2 largest radii) fits the source inside the container");
}

PourLattice pour_lattice(const Grains& grains, const Scene& scene, std::uint64_t seed, int max_batches,
                         double drop_gap) {
  if (grains.empty()) throw RelaxRefused("pour: no grains to pour");
  if (max_batches < 1) throw RelaxRefused("pour: max_batches must be at least 1, got " + std::to_string(max_batches));
  double r_max = 0.0;
  for (const Grain& g : grains) r_max = std::max(r_max, g.r);
  const std::vector<Site> sites = pour_sites(scene, r_max);
  const std::vector<DemWall> walls = dem_walls(scene.container, scene.dimension);
  PourLattice L;
  L.spacing = kPourSpacing * r_max;
  L.sites_per_layer = sites.size();
  L.layers = (grains.size() + sites.size() - 1) / sites.size();
  L.layers_per_batch = std::max<std::size_t>(1, (L.layers + max_batches - 1) / max_batches);
  const double jitter = kPourJitter * L.spacing;
  // Batch k is placed drop_gap + 2 r_max above the highest released centre, which is at most its predecessor's
  // top where nothing has settled yet (a fast pace): the released grains climb by at most drop_gap + 2 r_max +
  // a batch's thickness per batch, the held lattice's batches lie spacing > 2 r_max + 2 jitter apart, so a
  // lowest layer drop_gap x batches (+ the first batch's drop, the jitter and a few radii for bounces) up keeps
  // every held batch above the stream. The release checks it.
  const std::size_t n_batches = (L.layers + L.layers_per_batch - 1) / L.layers_per_batch;
  L.hold_base = static_cast<double>(n_batches + 1) * drop_gap + 6.0 * r_max + jitter;
  std::mt19937_64 rng(seed);
  auto draw = [&](double amplitude) { return amplitude * (2.0 * unit(rng) - 1.0); };
  std::vector<std::size_t> order(sites.size());
  L.grains = grains;
  for (std::size_t k = 0; k < grains.size(); ++k) {
    const std::size_t layer = k / sites.size(), slot = k % sites.size();
    if (slot == 0) {  // which sites a partial top layer takes: a shuffled order per layer
      for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
      for (std::size_t i = order.size(); i > 1; --i)
        std::swap(order[i - 1], order[static_cast<std::size_t>(unit(rng) * static_cast<double>(i))]);
    }
    const auto [x, y] = sites[order[slot]];
    const double lateral = std::clamp(lateral_clearance(walls, x, y) - 1.01 * r_max, 0.0, jitter);
    Grain& g = L.grains[k];
    g.x.x() = x + draw(lateral);
    g.x.y() = scene.dimension == 3 ? y + draw(lateral) : 0.0;
    g.x.z() = L.hold_base + static_cast<double>(layer) * L.spacing + draw(jitter);
    if (scene.container.kind == ContainerKind::Periodic) {
      g.x.x() = wrap(g.x.x(), scene.container.size_x);
      if (scene.dimension == 3) g.x.y() = wrap(g.x.y(), scene.container.size_y);
    }
  }
  const std::size_t per_batch = sites.size() * L.layers_per_batch;
  for (std::size_t first = 0; first < grains.size(); first += per_batch)
    L.batches.push_back({first, std::min(grains.size(), first + per_batch) - 1, 0});
  return L;
}

double pour_drop_gap(const Grains& grains, const PourSettings& settings) {
  double sum = 0.0;
  for (const Grain& g : grains) sum += g.r;
  return grains.empty() ? 0.0 : settings.drop_gap * 2.0 * sum / static_cast<double>(grains.size());
}

Scene pour_scene(const Scene& scene, const PourSettings& settings) {
  Scene s = scene;
  RelaxSpec& r = s.relax;
  if (settings.stop_ratio) r.stop_kinetic_ratio = *settings.stop_ratio;
  if (settings.settle_max_time) r.max_time = *settings.settle_max_time;
  if (settings.timestep_fraction) {
    r.timestep_fraction = *settings.timestep_fraction;
    r.timestep.reset();  // a fraction asked for replaces the scene's explicit step
  }
  r.stop_rule = "kinetic-energy";
  r.damping = 0.0;
  r.preload = false;
  r.target_phi.reset();
  return s;
}

RelaxPlan make_pour_plan(const PourLattice& lattice, const Scene& pour, const PourSettings& settings,
                         const std::string& engine, const Grains* footprint) {
  if (!(settings.pace > 0.0)) throw RelaxRefused("pour: pace must be positive, got " + g6(settings.pace));
  if (!(settings.drop_gap >= 0.0)) throw RelaxRefused("pour: drop gap must be >= 0, got " + g6(settings.drop_gap));
  if (!(settings.check_interval > 0.0))
    throw RelaxRefused("pour: check interval must be positive, got " + g6(settings.check_interval));
  if (settings.np < 1) throw RelaxRefused("pour: np must be >= 1, got " + std::to_string(settings.np));
  Packing start;
  start.grains = lattice.grains;
  RelaxSettings rs;
  rs.np = settings.np;
  rs.wall_time_limit = settings.wall_time_limit;
  RelaxPlan plan = make_plan(start, pour, rs, engine);
  const Grains& g = lattice.grains;
  double r_min = std::numeric_limits<double>::infinity(), r_max = 0.0;
  for (const Grain& x : g) r_min = std::min(r_min, x.r), r_max = std::max(r_max, x.r);
  PourRelease& rel = plan.pour;
  rel.enabled = true;
  rel.r_max = r_max;
  rel.drop_gap = pour_drop_gap(g, settings);
  for (PourRelease::Batch b : lattice.batches) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t i = b.first; i <= b.last; ++i) lo = std::min(lo, g[i].x.z()), hi = std::max(hi, g[i].x.z());
    const double fall = std::sqrt(2.0 * (rel.drop_gap + hi - lo + 2.0 * r_max) / kGravity);
    b.steps = std::max(1L, static_cast<long>(std::ceil(settings.pace * fall / plan.timestep)));
    rel.batches.push_back(b);
  }
  rel.steps_per_check = std::max(1L, static_cast<long>(std::ceil(settings.check_interval / plan.timestep)));
  // The settle's checks fall on multiples of the check window (LIGGGHTS' fix ave/time is current only there):
  // the last batch runs on to the next multiple.
  const long window = check_schedule(g, pour, plan).steps_per_check;
  long released = 0;
  for (const PourRelease::Batch& b : rel.batches) released += b.steps;
  rel.batches.back().steps += (window - released % window) % window;
  rel.release_time = static_cast<double>(released + (window - released % window) % window) * plan.timestep;
  plan.arming_time = rel.release_time + std::sqrt(2.0 * r_min / kGravity);
  if (plan.has_region && footprint) {  // the grains' earlier packing bounds the region too
    const double margin = pour.relax.open_margin * 2.0 * r_max;
    for (const Grain& x : *footprint)
      for (int a = 0; a < 2; ++a)
        plan.region_lo[a] = std::min(plan.region_lo[a], x.x[a] - x.r - margin),
        plan.region_hi[a] = std::max(plan.region_hi[a], x.x[a] + x.r + margin);
  }
  return plan;
}

Grains scene_drop_grains(const Scene& scene, std::uint64_t seed) {
  if (scene.clusters) refuse_scene_field(scene, "[clusters]", "the pour releases single grains, not rigid clusters");
  DropSequence drops(scene, seed);
  Grains grains(static_cast<std::size_t>(drops.count()));
  for (Grain& g : grains) {
    const Drop d = drops.next();
    g.x = Vec3::Zero();
    g.r = d.r;
    g.species = d.species;
  }
  return grains;
}

}  // namespace btr
