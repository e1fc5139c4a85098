// Time-step rules against values computed by hand (numbers below worked out separately, step by step).
#include <gtest/gtest.h>

#include <cmath>

#include "coupling/dem/timestep.h"
#include "relax_fixtures.h"

namespace {

btr::Scene one_species(double density, double young, double poisson, double restitution, const std::string& model) {
  btr::Scene s = btr_test::make_scene("ts", 3, btr_test::container(btr::ContainerKind::Periodic));
  s.grains.components[0].density = density;
  s.grains.components[0].material.young = young;
  s.grains.components[0].material.poisson = poisson;
  s.grains.components[0].material.restitution = restitution;
  s.relax.model = model;
  return s;
}

btr::Grains two_grains(double r1, double r2) {
  btr::Grains g(2);
  g[0].x = btr::Vec3(0, 0, r1);
  g[0].r = r1;
  g[1].x = btr::Vec3(0.01, 0, r2);
  g[1].r = r2;
  return g;
}

}  // namespace

// Glass, R = 1 mm, rho = 2500 kg/m^3, E = 63 GPa, nu = 0.2:
//   G = 63e9 / 2.4 = 2.625e10 Pa; sqrt(rho/G) = sqrt(9.5238e-8) = 3.08607e-4 s/m
//   T_R = pi * 1e-3 * 3.08607e-4 / (0.1631*0.2 + 0.8766 = 0.90922) = 1.066317e-6 s
TEST(Timestep, RayleighGlass) {
  EXPECT_NEAR(btr::rayleigh_time(1e-3, 2500, 63e9, 0.2), 1.066317e-6, 1e-12);
}

// Soft grain (rubber-like), R = 1 mm, rho = 1100, E = 1 MPa, nu = 0.45:
//   G = 1e6 / 2.9 = 3.44828e5 Pa; sqrt(rho/G) = sqrt(3.19e-3) = 5.64801e-2
//   T_R = pi * 1e-3 * 5.64801e-2 / (0.1631*0.45 + 0.8766 = 0.949995) = 1.867772e-4 s
TEST(Timestep, RayleighSoft) {
  EXPECT_NEAR(btr::rayleigh_time(1e-3, 1100, 1e6, 0.45), 1.867772e-4, 1e-10);
}

// The Hertz stable step uses the smallest grain and the scene's fraction, and says so.
TEST(Timestep, HertzStableStepUsesSmallestGrain) {
  const btr::Scene s = one_species(2500, 63e9, 0.2, 0.9, "hertz");
  const btr::StableStep st = btr::stable_timestep(two_grains(1e-3, 0.5e-3), s);
  // T_R scales with R: 0.5 mm gives 5.331584e-7 s; x 0.2 = 1.066317e-7 s; e = 0.9:
  // zeta = 0.1053605 / sqrt(pi^2 + 0.0111008) = 0.0335185, factor sqrt(1 + zeta^2) - zeta = 0.9670432.
  EXPECT_NEAR(st.characteristic_time, 5.331584e-7, 1e-12);
  EXPECT_NEAR(st.damping_factor, 0.9670432, 1e-7);
  EXPECT_NEAR(st.step, 1.066317e-7 * 0.9670432, 1e-12);
  EXPECT_NE(st.rule.find("Rayleigh"), std::string::npos) << st.rule;
  EXPECT_NE(st.rule.find("0.0005"), std::string::npos) << st.rule;  // the radius it used
}

// Hooke, glass pair R = 1 mm, e = 0.9, V = sqrt(2 g 2 mm) = 0.198091 m/s:
//   m = 4/3 pi 1e-9 2500 = 1.047198e-5 kg, m* = 5.235988e-6 kg, R* = 5e-4 m
//   Y* = 1 / (2 (1 - 0.04) / 63e9) = 3.28125e10 Pa
//   k = 16/15 sqrt(R*) Y* (15 m* V^2 / (16 sqrt(R*) Y*))^(1/5) = 5.989464e5 N/m
//   gamma_n = sqrt(4 m* k / (1 + (pi / ln 0.9)^2)) = 0.1187154 kg/s
//   t_c = pi / sqrt(k/m* - (gamma_n / 2m*)^2) = 9.293928e-6 s
TEST(Timestep, HookeGlassPair) {
  const double v = std::sqrt(2 * 9.81 * 2e-3);
  const double m = 4.0 / 3.0 * M_PI * 1e-9 * 2500;
  const double k = btr::hooke_stiffness(5e-4, m / 2, 3.28125e10, v);
  EXPECT_NEAR(k, 5.989464e5, 1.0);
  const double g = btr::hooke_damping(m / 2, k, 0.9);
  EXPECT_NEAR(g, 0.1187154, 1e-6);
  EXPECT_NEAR(btr::hooke_contact_time(k, m / 2, g), 9.293928e-6, 1e-11);

  const btr::Scene s = one_species(2500, 63e9, 0.2, 0.9, "hooke");
  const btr::StableStep st = btr::stable_timestep(two_grains(1e-3, 1e-3), s);
  EXPECT_NEAR(st.characteristic_time, 9.293928e-6, 1e-11);  // the pair is stiffer than a grain on a wall
  // damping: sqrt(1 - zeta^2) (sqrt(1 + zeta^2) - zeta) = 0.9994382 * 0.9670432 = 0.9664999
  EXPECT_NEAR(st.step, 0.2 * 9.293928e-6 * 0.9664999, 1e-11);
  EXPECT_NE(st.rule.find("contact time"), std::string::npos) << st.rule;
}

// Hooke, soft pair R = 1 mm, rho = 1100, E = 1 MPa, nu = 0.45, e = 0.5: k = 85.31757 N/m,
// gamma_n = 6.041280e-3 kg/s, t_c = 5.286616e-4 s.
TEST(Timestep, HookeSoftPair) {
  const btr::Scene s = one_species(1100, 1e6, 0.45, 0.5, "hooke");
  const btr::StableStep st = btr::stable_timestep(two_grains(1e-3, 1e-3), s);
  EXPECT_NEAR(st.characteristic_time, 5.286616e-4, 1e-9);
}

// A stiffer second species sets the Hertz step even though its grains are larger.
TEST(Timestep, StiffestSpeciesWins) {
  btr::Scene s = one_species(2500, 5e7, 0.3, 0.5, "hertz");
  btr::Component glass = s.grains.components[0];
  glass.species = 2;
  glass.material.young = 63e9;
  glass.material.poisson = 0.2;
  s.grains.components.push_back(glass);
  btr::Grains g = two_grains(0.5e-3, 1e-3);
  g[1].species = 2;
  const btr::StableStep st = btr::stable_timestep(g, s);
  EXPECT_NEAR(st.characteristic_time, 1.066317e-6, 1e-12);
}

// Strong damping shortens the stable step: e = 0.05 gives zeta = 2.995732 / sqrt(pi^2 + 8.974412)
// = 0.6901067 and a Verlet factor sqrt(1 + zeta^2) - zeta = 0.5249024.
TEST(Timestep, LowRestitutionShortensTheStep) {
  EXPECT_NEAR(btr::damping_ratio(0.05), 0.6901067, 1e-6);
  EXPECT_EQ(btr::damping_ratio(1.0), 0.0);
  const btr::Scene s = one_species(2500, 63e9, 0.2, 0.05, "hertz");
  const btr::StableStep st = btr::stable_timestep(two_grains(1e-3, 1e-3), s);
  EXPECT_NEAR(st.damping_factor, 0.5249024, 1e-6);
  EXPECT_NEAR(st.step, 0.2 * 0.5249024 * 1.066317e-6, 1e-12);
  EXPECT_NE(st.rule.find("damping factor"), std::string::npos) << st.rule;
}

// YADE puts the normal dashpot on the tangential motion too: for glass (nu = 0.2) kappa = 2 (0.8) / 1.8
// = 0.888889, the tangential damping ratio at e = 0.05 is 0.6901067 sqrt(7 / (2 kappa)) = 1.369388 and
// the factor sqrt(1 + 1.369388^2) - 1.369388 = 0.3262604 (against 0.5249024 for the normal mode).
TEST(Timestep, YadeTangentialDampingShortensTheStepFurther) {
  const btr::Scene s = one_species(2500, 63e9, 0.2, 0.05, "hertz");
  const btr::StableStep st = btr::stable_timestep(two_grains(1e-3, 1e-3), s, btr::DampedMode::TangentialSameDashpot);
  EXPECT_NEAR(st.damping_factor, 0.3262604, 1e-6);
  EXPECT_NEAR(st.step, 0.2 * 0.3262604 * 1.066317e-6, 1e-12);
  EXPECT_NE(st.rule.find("tangential"), std::string::npos) << st.rule;
}

// hooke-stiffness (seed 003, d = 1 mm, rho = 2400): m = 1.2566371e-6 kg, kn = 24.655 N/m,
// gamma_n = 4952.4 1/s. Grain pair: m_eff = m/2, pi / sqrt(kn/m_eff - (gamma_n/2)^2) = 5.459877e-4 s;
// grain on a wall: m_eff = m, 8.554053e-4 s. The pair is the shorter.
TEST(Timestep, HookeStiffnessContactTimeFromKnAndMass) {
  btr::Scene s = one_species(2400, 5e6, 0.3, 0.26, "hooke-stiffness");
  s.grains.components[0].material.kn = 24.655;
  s.grains.components[0].material.kt = 24.655 * 2 / 7;
  s.grains.components[0].material.gamma_n = 4952.4;
  const btr::StableStep st = btr::stable_timestep(two_grains(5e-4, 5e-4), s);
  EXPECT_NEAR(st.characteristic_time, 5.459877e-4, 1e-9);
  EXPECT_NE(st.rule.find("hooke-stiffness"), std::string::npos) << st.rule;
  // gamma_n above 2 sqrt(kn/m_eff) = 12531 1/s: no oscillation, no contact time: refused.
  s.grains.components[0].material.gamma_n = 13000;
  EXPECT_THROW(btr::stable_timestep(two_grains(5e-4, 5e-4), s), std::runtime_error);
}
