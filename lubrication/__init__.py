"""Geometry of confinement, small-object and near-critical asymptotics, and the
Secomb-Skalak / Barakat-Shaqfeh lubrication solver for a vesicle in a tube, or a red cell whose
membrane also resists in-plane shear (:mod:`lubrication.membrane`).

Scalings used everywhere: lengths by the volume radius R0 (tube radius R where named), velocities
by the mean Poiseuille velocity U, extra pressure drop dp_plus_R0 = dp+ R0/(eta U).
"""

from .checks import CannotPassError, InvalidParameterError, OutOfRangeWarning, ValidityRange
from .geometry import (
    area_radius, cell_from_volume_area, check_passes, clearance, confinement_from_diameter,
    critical_confinement, critical_diameter_um, critical_length, critical_length_um,
    critical_reduced_volume, reduced_area_excess, reduced_volume, volume_radius,
)
from .results import Status

__all__ = [
    "CannotPassError", "InvalidParameterError", "OutOfRangeWarning", "Status", "ValidityRange",
    "area_radius", "cell_from_volume_area", "check_passes", "clearance", "confinement_from_diameter",
    "critical_confinement", "critical_diameter_um", "critical_length", "critical_length_um",
    "critical_reduced_volume", "reduced_area_excess", "reduced_volume", "volume_radius",
]

__version__ = "0.1.0"
