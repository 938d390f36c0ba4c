"""Light transport: numpy arrays in, arrays out. No files, no PyVista, no UI."""

from .appearance import appearance_of, medium_from_appearance
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
    "appearance_of",
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
    "medium_from_appearance",
    "refract",
    "standard_dipole_profile",
    "standard_dipole_total_reflectance",
]
