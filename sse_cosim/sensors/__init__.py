"""Sensor layer: pure geometry of what each sensor sees and measures at one step.

- :mod:`.geometry`: sectors, vectorized in-sector and line-of-sight tests, shadows, regions.
- :mod:`.kernels`: the compiled shadow points (numba), beside their NumPy reference.
- :mod:`.kinds`: what each kind of sensor sees and measures (camera, range), by name.
- :mod:`.spec`: sensor specs from the scenario and their world poses on their carriers.
- :mod:`.measurement`: y = H p + v as strips (paper eqs. senmodel and strip), noise draws.
- :mod:`.observe`: every sensor's observation of a snapshot.
"""

from sse_cosim.sensors.geometry import (
    Boxes,
    box_distances,
    box_distances_reference,
    clear_mask,
    in_sector,
    line_of_sight,
    sector_mask,
    sector_polygon,
    shadow_points_reference,
    shadow_polygons,
    sight_masks,
    sight_masks_reference,
    visibility_regions,
)
from sse_cosim.sensors.kinds import Camera, RangeBearing, SensorKind
from sse_cosim.sensors.measurement import (
    Detection,
    NoiseKind,
    draw_noise,
    measure,
    measurement_matrix,
)
from sse_cosim.sensors.observe import SensorObservation, observe, seen_mask
from sse_cosim.sensors.spec import SensorSpec, find_carrier, locate, specs_from_scenario

__all__ = [
    "Boxes",
    "Camera",
    "Detection",
    "NoiseKind",
    "RangeBearing",
    "SensorKind",
    "SensorObservation",
    "SensorSpec",
    "box_distances",
    "box_distances_reference",
    "clear_mask",
    "draw_noise",
    "find_carrier",
    "in_sector",
    "line_of_sight",
    "locate",
    "measure",
    "measurement_matrix",
    "observe",
    "sector_mask",
    "sector_polygon",
    "seen_mask",
    "shadow_points_reference",
    "shadow_polygons",
    "sight_masks",
    "sight_masks_reference",
    "specs_from_scenario",
    "visibility_regions",
]
