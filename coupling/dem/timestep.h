#pragma once
// Stable time steps for the DEM relaxation (docs/design.md section 4), shared by both engines.
//  Hertz: Rayleigh time  T_R = pi R sqrt(rho / G) / (0.1631 nu + 0.8766), G = Y / (2 (1 + nu)),
//         of the grain that gives the smallest T_R (the smallest grain of its species).
//  Hooke: contact time   t_c = pi / sqrt(k / m_eff - (gamma / 2)^2), gamma = gamma_n / m_eff, with
//         k and gamma_n as LIGGGHTS "model hooke" computes them from the materials and the
//         characteristic impact velocity V, for the stiffest contact the packing can make.
// The stable step is timestep_fraction times that time, times a damping factor: velocity Verlet on a
// damped oscillator is stable only for dt < (2/omega_0)(sqrt(1 + zeta^2) - zeta), so strong damping
// (low restitution) shortens the step. zeta is the damping ratio of the lowest restitution in the
// scene, zeta = -ln e / sqrt(pi^2 + ln^2 e). Hertz: factor sqrt(1 + zeta^2) - zeta; Hooke, whose
// contact time already grows by 1 / sqrt(1 - zeta^2) with damping: sqrt(1 - zeta^2)(sqrt(1 + zeta^2) - zeta).
#include <string>

#include "btr/model/grain.h"
#include "btr/scene/scene.h"

namespace btr {

double rayleigh_time(double radius, double density, double young, double poisson);

// LIGGGHTS "model hooke": k_n = 16/15 sqrt(R*) Y* (15 m* V^2 / (16 sqrt(R*) Y*))^(1/5).
double hooke_stiffness(double r_eff, double m_eff, double y_eff, double velocity);
// gamma_n = sqrt(4 m* k_n / (1 + (pi / ln e)^2)) (0 for e = 1).
double hooke_damping(double m_eff, double stiffness, double restitution);
// pi / sqrt(k / m* - (gamma_n / (2 m*))^2).
double hooke_contact_time(double stiffness, double m_eff, double damping);
// The characteristic impact velocity written for "model hooke": the speed of a grain that fell
// through the largest diameter of the packing, sqrt(2 g d_max) (the scale of BTR's rearrangements).
double hooke_characteristic_velocity(const Grains& grains);

// Damping ratio of a contact of restitution e (0 for e = 1).
double damping_ratio(double restitution);
// The lowest restitution of any contact the scene can make (grain pairs take the mean, walls the grain's).
double lowest_restitution(const Scene& scene);

struct StableStep {
  double characteristic_time = 0.0;  // T_R or t_c [s]
  double fraction = 0.0;             // scene relax.timestep_fraction
  double damping_factor = 1.0;       // see above
  double step = 0.0;                 // fraction * damping_factor * characteristic_time [s]
  std::string rule;                  // one line naming the rule, the grain(s) and the numbers
};

// Which damping ratio sets the damping factor. LIGGGHTS damps the tangential motion with its own
// coefficient; YADE's Hertz-Mindlin and linear laws put the normal viscous coefficient on the
// tangential dashpot too, where the mode of a rolling sphere has mass 2/7 m and stiffness kappa k_n
// (Hertz-Mindlin: kappa = 2 (1 - nu) / (2 - nu); linear law: kappa = 1), so its damping ratio is
// sqrt(7 / (2 kappa)) times the normal one.
enum class DampedMode { Normal, TangentialSameDashpot };

// Throws std::runtime_error for an empty packing or a species the scene does not have.
StableStep stable_timestep(const Grains& grains, const Scene& scene, DampedMode mode = DampedMode::Normal);

}  // namespace btr
