"""Light transport: numpy arrays in, arrays out. No files, no PyVista, no UI."""

from .dipoles import (
    better_dipole_profile,
    better_dipole_total_reflectance,
    directional_dipole,
    directional_dipole_profile,
    directional_dipole_total_reflectance,
    standard_dipole_profile,
    standard_dipole_total_reflectance,
)
from .fresnel import fresnel_reflectance, fresnel_transmittance, refract
from .materials import Material, catalogue, material, material_names
from .medium import Medium

__all__ = [
    "Material",
    "Medium",
    "better_dipole_profile",
    "better_dipole_total_reflectance",
    "catalogue",
    "directional_dipole",
    "directional_dipole_profile",
    "directional_dipole_total_reflectance",
    "fresnel_reflectance",
    "fresnel_transmittance",
    "material",
    "material_names",
    "refract",
    "standard_dipole_profile",
    "standard_dipole_total_reflectance",
]
