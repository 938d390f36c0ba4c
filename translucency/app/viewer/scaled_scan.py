"""The scan as a viewer solves it: the mesh as loaded, its name and orientation, and the Scene at the scale chosen.

:meth:`ScaledScan.load` loads (or converts) the scan once; :meth:`ScaledScan.scaled` gives the same scan at
another size of one unit of its file, with a new :class:`~translucency.app.shading.scene.Scene` of the scaled mesh.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ...errors import InvalidParameterError
from ..framing import front_direction, turned_to_front
from ..shading.scan import mesh_for_shading
from ..shading.scene import Scene, scene_for
from ..shading.settings import ShadeSettings, default_light_direction


@dataclasses.dataclass(eq=False)
class ScaledScan:
    """A scan at the scale a viewer shows it.

    Attributes
    ----------
    base_mesh : TriangleMesh
        The cleaned mesh as loaded, mm.
    name : str
        Stem of saved files.
    up_axis : str
        The scan's up, ``"+x"`` ... ``"-z"``.
    up : tuple of 3 float
        The same as a unit vector.
    front : numpy.ndarray
        Toward the camera that sees the scan's front (:func:`~translucency.app.framing.front_direction`).
    mm_per_unit : float
        Size of one unit of the mesh's file, mm.
    scene : Scene
        The persistent Scene of the mesh at that scale.
    """

    base_mesh: object
    name: str
    up_axis: str
    up: tuple
    front: np.ndarray
    mm_per_unit: float
    scene: Scene

    @classmethod
    def load(cls, mesh, settings: ShadeSettings, *, unit=None, name=None) -> ScaledScan:
        """The scan of ``mesh`` (a cleaned TriangleMesh in mm, a PolyData in ``unit``, or None for the embedded
        default scan), its Scene made with the shadows and up axis of ``settings``; ``name`` defaults to the
        file's stem (or ``scan``)."""
        from ...io.upright import up_vector
        from ..shading.scan import load_scan

        if mesh is None:
            mesh, _, default_name = load_scan(None)
            name = name or default_name
        else:
            mesh = mesh_for_shading(mesh, unit, entry="Viewer")
        name = name or (Path(mesh.source).stem if mesh.source is not None else "scan")
        scene = scene_for(mesh, settings)
        up = tuple(float(u) for u in up_vector(scene.up))
        return cls(mesh, name, scene.up, up, front_direction(mesh, up), float(mesh.mm_per_unit), scene)

    def scaled(self, mm_per_unit, *, shadows: bool) -> ScaledScan | None:
        """This scan with one unit of its file ``mm_per_unit`` mm (a positive number) and a new Scene (``shadows``
        as given, the same up); None when that is the current scale.

        The points become ``p * mm_per_unit / m0`` with ``m0`` the mesh's own mm per unit.
        """
        mm_per_unit = float(mm_per_unit)
        if not (np.isfinite(mm_per_unit) and mm_per_unit > 0):
            raise InvalidParameterError(f"the scale must be a positive number of mm per unit, got {mm_per_unit!r}.")
        if mm_per_unit == self.mm_per_unit:
            return None
        factor = mm_per_unit / float(self.base_mesh.mm_per_unit)
        mesh = self.base_mesh.replace(points=self.base_mesh.points * factor, mm_per_unit=mm_per_unit)
        return dataclasses.replace(self, mm_per_unit=mm_per_unit, scene=Scene(mesh, shadows=shadows, up=self.up_axis))

    def front_light(self):
        """The viewer's default light: one white directional light of 1 W/m² above and in front of the scan
        (:func:`~translucency.app.shading.settings.default_light_direction` of :attr:`up_axis`, turned about
        ``up`` with the camera to the scan's :attr:`front`, :mod:`translucency.app.framing`)."""
        from ...scatter.lights import DirectionalLight

        return DirectionalLight(turned_to_front(default_light_direction(self.up_axis), self.up, self.front), 1.0)
