#include "btr/placement/drops.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "btr/scene/scene_toml.h"

namespace btr {

namespace {
// x^k by multiplication: exact IEEE arithmetic, so mixture thresholds are the same on every machine.
double ipow(double x, int k) {
  double p = 1.0;
  for (int i = 0; i < k; ++i) p *= x;
  return p;
}
}  // namespace

double radius_moment(const RadiusSpec& spec, int k) {
  switch (spec.kind) {
    case RadiusSpec::Kind::Constant: return ipow(spec.value, k);
    case RadiusSpec::Kind::Uniform: {
      const double a = spec.min, b = spec.max;
      return (ipow(b, k + 1) - ipow(a, k + 1)) / ((k + 1) * (b - a));
    }
    case RadiusSpec::Kind::ConstantMass: {
      // Eq. 1 gives the density p(R) = a b / ((b - a) R^2) on [a, b].
      const double a = spec.min, b = spec.max, c = a * b / (b - a);
      if (k == 1) return c * std::log(b / a);
      return c * (ipow(b, k - 1) - ipow(a, k - 1)) / (k - 1);
    }
    case RadiusSpec::Kind::List: {
      double s = 0.0;
      for (double r : spec.list) s += ipow(r, k);
      return spec.list.empty() ? 0.0 : s / static_cast<double>(spec.list.size());
    }
  }
  return 0.0;
}

std::vector<double> number_fractions(const GrainsSpec& grains, int dimension) {
  std::vector<double> f;
  double sum = 0.0;
  for (const auto& c : grains.components) {
    double v = c.fraction;
    if (grains.fraction_by == GrainsSpec::FractionBy::Volume) v /= radius_moment(c.radius, dimension);
    f.push_back(v);
    sum += v;
  }
  for (double& v : f) v /= sum;
  return f;
}

DropSequence::DropSequence(const Scene& scene, std::uint64_t seed)
    : dimension_(scene.dimension),
      container_(scene.container),
      source_(scene.source),
      components_(scene.grains.components),
      list_pos_(scene.grains.components.size(), 0),
      rng_(seed),
      count_(scene.grains.count) {
  if (scene.container.kind == ContainerKind::Mesh) mesh_ = std::make_shared<const MeshIndex>(*scene.container.mesh, std::max(scene.container.size_x, scene.container.size_y) / 64.0);
  r_min_ = std::numeric_limits<double>::infinity();
  r_max_ = 0.0;
  if (source_.kind == SourceSpec::Kind::List) {
    listed_ = read_drop_list(source_.file, dimension_);
    if (static_cast<std::int64_t>(listed_.size()) < count_)
      throw SceneError(source_.file + ": expected at least " + std::to_string(count_) + " drops, got " +
                       std::to_string(listed_.size()) + " rows");
    listed_.resize(static_cast<std::size_t>(count_));
    for (const auto& d : listed_) r_min_ = std::min(r_min_, d.r), r_max_ = std::max(r_max_, d.r);
    check_mesh_footprint(scene);
    return;
  }
  if (scene.intruder) {
    // Dropped first and drawing no random numbers, so the bed's drops are those of the scene without it.
    intruder_ = scene.intruder;
    ++count_;
    const double r = scene.intruder->diameter_ratio * components_[0].radius.value;
    r_min_ = std::min(r_min_, r), r_max_ = std::max(r_max_, r);
  }
  const auto fractions = number_fractions(scene.grains, dimension_);
  double cum = 0.0;
  for (std::size_t i = 0; i < components_.size(); ++i) {
    cum += fractions[i];
    cumulative_.push_back(cum);
    if (fractions[i] <= 0.0) continue;
    const RadiusSpec& r = components_[i].radius;
    switch (r.kind) {
      case RadiusSpec::Kind::Constant: r_min_ = std::min(r_min_, r.value), r_max_ = std::max(r_max_, r.value); break;
      case RadiusSpec::Kind::List:
        r_min_ = std::min(r_min_, *std::min_element(r.list.begin(), r.list.end()));
        r_max_ = std::max(r_max_, *std::max_element(r.list.begin(), r.list.end()));
        break;
      default: r_min_ = std::min(r_min_, r.min), r_max_ = std::max(r_max_, r.max);
    }
  }
  check_mesh_footprint(scene);
}

// A mesh container's point, region and list sources are checked against its footprint before any grain
// is placed: the largest grain at the point (and around its scatter circle), the region's corners and
// centre, every listed drop. The rain draws only inside it (position).
void DropSequence::check_mesh_footprint(const Scene& scene) const {
  if (!mesh_) return;
  const SourceSpec& s = source_;
  auto refuse_if_outside = [&](double x, double y, double r, const std::string& where) {
    const std::string why = mesh_->footprint_misfit(x, y, r);
    if (!why.empty())
      throw SceneError(scene.file + ": " + where + ": expected drops that land inside the mesh container, got " + why);
  };
  switch (s.kind) {
    case SourceSpec::Kind::Point:
      refuse_if_outside(s.x, s.y, r_max_, "source.position");
      for (int k = 0; k < 8 && s.scatter > 0.0; ++k)
        refuse_if_outside(s.x + s.scatter * std::cos(k * M_PI / 4), s.y + s.scatter * std::sin(k * M_PI / 4), r_max_,
                          "source.scatter");
      break;
    case SourceSpec::Kind::Region:
      for (double x : {s.x_min, 0.5 * (s.x_min + s.x_max), s.x_max})
        for (double y : {s.y_min, 0.5 * (s.y_min + s.y_max), s.y_max}) refuse_if_outside(x, y, r_max_, "source.x, source.y");
      break;
    case SourceSpec::Kind::List:
      for (const ListedDrop& d : listed_)
        refuse_if_outside(d.x, d.y, d.r, s.file + ":" + std::to_string(d.line));
      break;
    case SourceSpec::Kind::Rain: break;
  }
}

double DropSequence::uniform() { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }

double DropSequence::radius(std::size_t i) {
  const RadiusSpec& r = components_[i].radius;
  switch (r.kind) {
    case RadiusSpec::Kind::Constant: return r.value;
    case RadiusSpec::Kind::Uniform: return r.min + uniform() * (r.max - r.min);
    case RadiusSpec::Kind::ConstantMass: return r.min * r.max / (r.max - uniform() * (r.max - r.min));
    case RadiusSpec::Kind::List: {
      const double v = r.list[list_pos_[i]];
      list_pos_[i] = (list_pos_[i] + 1) % r.list.size();
      return v;
    }
  }
  return 0.0;
}

void DropSequence::disk(double radius, double& x, double& y) {
  double u, v;
  do {
    u = 2.0 * uniform() - 1.0;
    v = 2.0 * uniform() - 1.0;
  } while (u * u + v * v >= 1.0);
  x = radius * u;
  y = radius * v;
}

void DropSequence::position(double r, Drop& d) {
  const bool three = dimension_ == 3;
  const Container& c = container_;
  switch (source_.kind) {
    case SourceSpec::Kind::Point:
      if (three) {
        double dx, dy;
        disk(source_.scatter, dx, dy);
        d.x = source_.x + dx, d.y = source_.y + dy;
      } else {
        d.x = source_.x + source_.scatter * (2.0 * uniform() - 1.0);
      }
      break;
    case SourceSpec::Kind::Region:
      d.x = source_.x_min + uniform() * (source_.x_max - source_.x_min);
      if (three) d.y = source_.y_min + uniform() * (source_.y_max - source_.y_min);
      break;
    case SourceSpec::Kind::Rain:
      switch (c.kind) {
        case ContainerKind::Cylinder: disk(c.radius - r, d.x, d.y); break;
        case ContainerKind::Drum:  // over the drum's width, clear of its end walls (over a period of periodic ends)
          d.x = -(c.radius - r) + uniform() * 2.0 * (c.radius - r);
          if (three && c.periodic_ends) d.y = -0.5 * c.size_y + uniform() * c.size_y;
          else if (three) d.y = (-0.5 * c.size_y + r) + uniform() * (c.size_y - 2.0 * r);
          break;
        case ContainerKind::Mesh: {
          // Uniform over the part of its bounding box where a grain lands inside (drawn again elsewhere).
          constexpr int kTries = 10000;
          for (int k = 0; k < kTries; ++k) {
            d.x = (-0.5 * c.size_x + r) + uniform() * (c.size_x - 2.0 * r);
            d.y = (-0.5 * c.size_y + r) + uniform() * (c.size_y - 2.0 * r);
            if (mesh_->in_footprint(d.x, d.y, r)) return;
          }
          throw PlacementError(drawn_ + 1, "the rain cannot reach the footprint of the mesh " + c.mesh->file + ": none of " +
                                               std::to_string(kTries) + " drops of radius " + std::to_string(r) +
                                               " over its bounding box lands inside it (last: " +
                                               mesh_->footprint_misfit(d.x, d.y, r) + ")");
        }
        case ContainerKind::Periodic:
          d.x = -0.5 * c.size_x + uniform() * c.size_x;
          if (three) d.y = -0.5 * c.size_y + uniform() * c.size_y;
          break;
        default: {  // box, hele-shaw: the grain stays clear of the walls
          d.x = (-0.5 * c.size_x + r) + uniform() * (c.size_x - 2.0 * r);
          const double w = c.kind == ContainerKind::HeleShaw ? c.gap : c.size_y;
          if (three) d.y = (-0.5 * w + r) + uniform() * (w - 2.0 * r);
        }
      }
      break;
    case SourceSpec::Kind::List: break;
  }
  if (wraps_x(c)) d.x = wrap_coordinate(d.x, c.size_x);
  if (wraps_y(c, dimension_)) d.y = wrap_coordinate(d.y, c.size_y);
  if (!three) d.y = 0.0;
}

Drop DropSequence::next() {
  if (drawn_ >= count_)
    throw std::out_of_range("DropSequence: all " + std::to_string(count_) + " drops were already drawn");
  Drop d;
  if (intruder_ && drawn_ == 0) {
    d.x = intruder_->x, d.y = dimension_ == 3 ? intruder_->y : 0.0;
    d.r = intruder_->diameter_ratio * components_[0].radius.value;
    d.species = intruder_->species;
    ++drawn_;
    return d;
  }
  if (source_.kind == SourceSpec::Kind::List) {
    const ListedDrop& l = listed_[static_cast<std::size_t>(drawn_)];
    d.x = l.x, d.y = l.y, d.r = l.r, d.species = l.species;
  } else {
    std::size_t i = 0;
    if (components_.size() > 1) {
      const double u = uniform();
      while (i + 1 < components_.size() && !(u < cumulative_[i])) ++i;
    }
    d.species = components_[i].species;
    d.r = radius(i);
  }
  position(d.r, d);
  ++drawn_;
  return d;
}

}  // namespace btr
