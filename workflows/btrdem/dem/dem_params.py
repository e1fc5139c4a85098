"""Material and time-step numbers shared by the DEM pour and the sweeps, from a scene (JSON form)."""
from __future__ import annotations

import math

import numpy as np

G = 9.81


def components(scene: dict) -> list:
    comps = (scene.get("grains") or {}).get("components") or []
    if not comps:
        raise ValueError("scene.grains.components: expected at least one component")
    return comps


def species_table(scene: dict) -> dict:
    """species -> {density, young, poisson, restitution, friction, rolling_friction}."""
    out = {}
    for c in components(scene):
        m = c["material"]
        out[int(c["species"])] = {"density": float(c["density"]), "young": float(m["young"]),
                                  "poisson": float(m["poisson"]), "restitution": float(m["restitution"]),
                                  "friction": float(m["friction"]),
                                  "rolling_friction": float(m.get("rolling_friction", 0.0))}
        for key in ("kn", "kt", "gamma_n", "gamma_t", "wall_gamma_t"):  # hooke-stiffness only
            out[int(c["species"])][key] = float(m.get(key, 0.0))
    return out


def rayleigh_time(radius: float, density: float, young: float, poisson: float) -> float:
    """pi R sqrt(rho / G) / (0.1631 nu + 0.8766), G = E / (2 (1 + nu)) (docs/design.md section 4)."""
    shear = young / (2.0 * (1.0 + poisson))
    return math.pi * radius * math.sqrt(density / shear) / (0.1631 * poisson + 0.8766)


def effective_young(a: dict, b: dict) -> float:
    return 1.0 / ((1 - a["poisson"] ** 2) / a["young"] + (1 - b["poisson"] ** 2) / b["young"])


def hooke_stiffness(r_eff, m_eff, y_eff, velocity) -> float:
    """LIGGGHTS "model hooke": k_n = 16/15 sqrt(R*) Y* (15 m* V^2 / (16 sqrt(R*) Y*))^(1/5)."""
    s = math.sqrt(r_eff)
    return 16.0 / 15.0 * s * y_eff * (15.0 * m_eff * velocity ** 2 / (16.0 * s * y_eff)) ** 0.2


def hooke_contact_time(r_eff, m_eff, y_eff, velocity, restitution) -> float:
    """LIGGGHTS "model hooke" stiffness and damping from the materials and the characteristic
    velocity, and the contact time pi / sqrt(k/m* - (gamma_n / 2 m*)^2) (coupling/dem/timestep.h)."""
    k = hooke_stiffness(r_eff, m_eff, y_eff, velocity)
    gamma = 0.0
    if restitution < 1.0:
        q = math.pi / math.log(restitution)
        gamma = math.sqrt(4.0 * m_eff * k / (1.0 + q * q))
    return math.pi / math.sqrt(k / m_eff - (gamma / (2.0 * m_eff)) ** 2)


def hooke_characteristic_velocity(radius) -> float:
    return math.sqrt(2.0 * G * 2.0 * float(np.max(radius)))


def stable_timestep(radius: np.ndarray, species: np.ndarray, scene: dict, fraction: float):
    """The coupling's rule (coupling/dem/timestep.h): Hertz, the smallest Rayleigh time over the species
    present (each with its smallest grain); Hooke, the shortest contact time over grain pairs and
    grain-wall contacts at the ends of each species' radius range. Times fraction.
    Returns (timestep, rule text)."""
    table = species_table(scene)
    if (scene.get("relax") or {}).get("model", "hertz") == "hooke-stiffness":
        # explicit stiffness: pi / sqrt(kn/m_eff - (gamma_n/2)^2), pairs (mean kn, gamma_n) and walls (m_eff = m)
        best, what = math.inf, ""
        present = [int(s) for s in np.unique(species)]
        for a in present:
            ra = radius[species == a]
            for r1 in (float(ra.min()), float(ra.max())):
                m1 = table[a]["density"] * 4.0 / 3.0 * math.pi * r1 ** 3
                cands = [(table[a]["kn"], table[a]["gamma_n"], m1, "wall")]
                for b in present:
                    rb = radius[species == b]
                    for r2 in (float(rb.min()), float(rb.max())):
                        m2 = table[b]["density"] * 4.0 / 3.0 * math.pi * r2 ** 3
                        cands.append((0.5 * (table[a]["kn"] + table[b]["kn"]),
                                      0.5 * (table[a]["gamma_n"] + table[b]["gamma_n"]), m1 * m2 / (m1 + m2), "pair"))
                for kn, gn, me, label in cands:
                    w2 = kn / me - 0.25 * gn * gn
                    if not w2 > 0:
                        raise ValueError(f"hooke-stiffness: {label} contact overdamped (kn {kn:g}, gamma_n {gn:g})")
                    t = math.pi / math.sqrt(w2)
                    if t < best:
                        best, what = t, f"{label}: kn = {kn:.4g} N/m, m_eff = {me:.4g} kg, gamma_n = {gn:.4g} 1/s"
        return best * fraction, (f"hooke-stiffness contact time {best:.4g} s ({what}) x {fraction:g} "
                                 f"= {best * fraction:.4g} s")
    if (scene.get("relax") or {}).get("model", "hertz") == "hooke":
        v = hooke_characteristic_velocity(radius)
        wall = table[int(components(scene)[0]["species"])]
        best = math.inf
        present = [int(s) for s in np.unique(species)]
        for a in present:
            ra = radius[species == a]
            for r1 in (float(ra.min()), float(ra.max())):
                m1 = table[a]["density"] * 4.0 / 3.0 * math.pi * r1 ** 3
                best = min(best, hooke_contact_time(r1, m1, effective_young(table[a], wall), v,
                                                    table[a]["restitution"]))
                for b in present:
                    rb = radius[species == b]
                    for r2 in (float(rb.min()), float(rb.max())):
                        m2 = table[b]["density"] * 4.0 / 3.0 * math.pi * r2 ** 3
                        e = 0.5 * (table[a]["restitution"] + table[b]["restitution"])
                        best = min(best, hooke_contact_time(r1 * r2 / (r1 + r2), m1 * m2 / (m1 + m2),
                                                            effective_young(table[a], table[b]), v, e))
        return best * fraction, (f"Hooke contact time {best:.4g} s (characteristic velocity {v:.4g} m/s) "
                                 f"x {fraction:g} = {best * fraction:.4g} s")
    best = None
    for s in np.unique(species):
        if int(s) not in table:
            raise ValueError(f"species {int(s)}: not among the scene's components {sorted(table)}")
        m = table[int(s)]
        r = float(np.min(radius[species == s]))
        t = rayleigh_time(r, m["density"], m["young"], m["poisson"])
        if best is None or t < best[0]:
            best = (t, r, int(s))
    t, r, s = best
    return t * fraction, (f"Rayleigh time {t:.4g} s (Hertz, smallest grain r = {r:.4g} m, species {s}) "
                          f"x {fraction:g} = {t * fraction:.4g} s")


def masses(radius: np.ndarray, species: np.ndarray, scene: dict, dimension: int = 3) -> np.ndarray:
    """Grain masses (spheres; disks are run as spheres in the x-z plane)."""
    table = species_table(scene)
    rho = np.array([table[int(s)]["density"] for s in species])
    return rho * 4.0 / 3.0 * math.pi * radius ** 3


def kinetic_threshold(radius, species, scene, ratio: float) -> float:
    """ratio * sum_i m_i g d_i: the energy to lift every grain by its own diameter."""
    return float(ratio * np.sum(masses(radius, species, scene) * G * 2.0 * radius))
