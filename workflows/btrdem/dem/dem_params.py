"""Material numbers from a scene (JSON form) for the stability sweep's estimates: species table, masses,
effective modulus, LIGGGHTS' Hooke stiffness, the kinetic threshold. The time-step rule is btr's alone
(coupling/dem/timestep.cpp): `btr relax` and `btr pour` record the step they used."""
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


def effective_young(a: dict, b: dict) -> float:
    return 1.0 / ((1 - a["poisson"] ** 2) / a["young"] + (1 - b["poisson"] ** 2) / b["young"])


def hooke_stiffness(r_eff, m_eff, y_eff, velocity) -> float:
    """LIGGGHTS "model hooke": k_n = 16/15 sqrt(R*) Y* (15 m* V^2 / (16 sqrt(R*) Y*))^(1/5)."""
    s = math.sqrt(r_eff)
    return 16.0 / 15.0 * s * y_eff * (15.0 * m_eff * velocity ** 2 / (16.0 * s * y_eff)) ** 0.2


def hooke_characteristic_velocity(radius) -> float:
    return math.sqrt(2.0 * G * 2.0 * float(np.max(radius)))


def masses(radius: np.ndarray, species: np.ndarray, scene: dict, dimension: int = 3) -> np.ndarray:
    """Grain masses (spheres; disks are run as spheres in the x-z plane)."""
    table = species_table(scene)
    rho = np.array([table[int(s)]["density"] for s in species])
    return rho * 4.0 / 3.0 * math.pi * radius ** 3


def kinetic_threshold(radius, species, scene, ratio: float) -> float:
    """ratio * sum_i m_i g d_i: the energy to lift every grain by its own diameter."""
    return float(ratio * np.sum(masses(radius, species, scene) * G * 2.0 * radius))
