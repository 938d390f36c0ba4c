"""Scan repair: turn a raw scan into a clean, consistently oriented triangle mesh, and report what changed.

The steps run in this order (each can be switched off); the order matters, for example islands are
removed before holes are closed (the border of a one-triangle island is a 3-edge "hole"), and
non-manifold vertices are split before components are counted.

==== ============================== =========== ===================================================
step what                           tool        how
==== ============================== =========== ===================================================
1    duplicate vertices             numpy       vertices at exactly the same position are merged
2    null faces                     numpy       triangles with a repeated index (also those the
                                                merge of step 1 creates) are removed
3    duplicate faces                numpy       triangles on the same three vertices as an earlier
                                                one are removed
4    zero-area faces                numpy       triangles with collinear corners (see
                                                :data:`~translucency.io.defects.ZERO_AREA_RATIO`)
                                                are removed
5    non-manifold edges             pymeshlab   ``meshing_repair_non_manifold_edges`` (removes the
                                                fewest faces that make every edge manifold)
6    non-manifold vertices          pymeshlab   ``meshing_repair_non_manifold_vertices`` (splits the
                                                vertex, one copy per fan)
7    small islands                  numpy       components with less than ``min_island_fraction``
                                                of the area of the largest are removed
8    coherent orientation           numpy       :mod:`translucency.geometry.orientation`
9    holes                          pymeshlab   ``meshing_close_holes`` on boundary loops of at most
                                                ``max_hole_edges`` edges (a pass that refuses
                                                self-intersecting patches, then one that does not)
10   outward orientation            numpy       coherent again, then every component flipped to a
                                                positive signed volume (heuristic for open ones)
11   unreferenced vertices          numpy       vertices no triangle uses are removed
12   normals                        numpy       area-weighted vertex normals, optionally smoothed
==== ============================== =========== ===================================================

Per-vertex properties follow their vertices (merged vertices keep the first copy's values, split
vertices copy the original's); the ``"normals"`` property is recomputed from the repaired surface.
The :class:`CleanReport` holds the defect counts before and after (:mod:`translucency.io.defects`)
and what every step changed, counted from the arrays themselves.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..errors import InvalidParameterError, MeshError
from ..geometry.measure import triangle_areas, vertex_measures, vertex_normals
from ..geometry.mesh import TriangleMesh, validate_mesh_arrays
from ..geometry.orientation import coherent_orientation, flip_triangles, outward_flips
from ..geometry.topology import (
    count_non_manifold_vertices,
    duplicate_triangles,
    face_components,
    first_at_same_position,
    unique_edges,
)
from .defects import ZERO_AREA_RATIO, MeshDefects, survey_mesh, zero_area_mask
from .polydata import as_triangle_mesh

__all__ = ["CleanReport", "clean_mesh", "clean_arrays", "smooth_vertex_normals"]

_ORIGIN = "translucency_origin"
_SPLIT_DISPLACEMENT = 0.01


@dataclasses.dataclass(frozen=True)
class CleanReport:
    """What :func:`clean_mesh` found and changed; every count is measured on the arrays.

    Attributes
    ----------
    before, after : MeshDefects
        Defect counts of the input and of the result.
    duplicate_vertices_merged : int
        Vertices removed because another vertex had exactly the same position.
    null_faces_removed : int
        Triangles with a repeated vertex index removed (including those the merge created).
    duplicate_faces_removed, zero_area_faces_removed : int
    non_manifold_edges_repaired : int
        Non-manifold edges found (and made manifold).
    non_manifold_edge_faces_removed : int
        Triangles removed to make those edges manifold.
    non_manifold_vertices_repaired : int
        Non-manifold vertices found after the edge repair (and split).
    non_manifold_vertices_added : int
        Vertices added by splitting them.
    islands_removed, island_faces_removed : int
        Small components removed and their triangles.
    holes_closed, hole_faces_added : int
        Boundary loops closed (as pymeshlab reports them: a loop left by a first patch and closed
        by the second pass counts again) and the net number of triangles added.
    faces_flipped_coherent : int
        Triangles reversed to make the orientation coherent.
    components_flipped_outward, faces_flipped_outward : int
        Components (and their triangles) reversed to face outward.
    non_orientable_components : int
        Components that admit no coherent orientation (left as they were).
    unreferenced_vertices_removed : int
        Vertices no triangle used (in the input, or left so by the removals above).
    normal_smoothing_iterations : int
    settings : dict
        The options the repair ran with.
    seconds : float
        Wall-clock time of the repair.
    """

    before: MeshDefects
    after: MeshDefects
    duplicate_vertices_merged: int = 0
    null_faces_removed: int = 0
    duplicate_faces_removed: int = 0
    zero_area_faces_removed: int = 0
    non_manifold_edges_repaired: int = 0
    non_manifold_edge_faces_removed: int = 0
    non_manifold_vertices_repaired: int = 0
    non_manifold_vertices_added: int = 0
    islands_removed: int = 0
    island_faces_removed: int = 0
    holes_closed: int = 0
    hole_faces_added: int = 0
    faces_flipped_coherent: int = 0
    components_flipped_outward: int = 0
    faces_flipped_outward: int = 0
    non_orientable_components: int = 0
    unreferenced_vertices_removed: int = 0
    normal_smoothing_iterations: int = 0
    settings: dict = dataclasses.field(default_factory=dict)
    seconds: float = 0.0

    @property
    def changed(self) -> bool:
        """True when the repair changed anything."""
        counts = dataclasses.asdict(self)
        for key in (
            "before",
            "after",
            "settings",
            "seconds",
            "normal_smoothing_iterations",
            "non_orientable_components",
        ):
            counts.pop(key)
        return any(counts.values())

    def summary(self) -> str:
        """A readable two-part table: what was repaired, and the defect counts before and after."""
        rows = [
            ("duplicate vertices merged", self.duplicate_vertices_merged),
            ("null faces removed (repeated index)", self.null_faces_removed),
            ("duplicate faces removed", self.duplicate_faces_removed),
            ("zero-area faces removed", self.zero_area_faces_removed),
            ("non-manifold edges repaired", self.non_manifold_edges_repaired),
            ("  faces removed for them", self.non_manifold_edge_faces_removed),
            ("non-manifold vertices repaired", self.non_manifold_vertices_repaired),
            ("  vertices added by splitting", self.non_manifold_vertices_added),
            ("small islands removed", self.islands_removed),
            ("  faces removed with them", self.island_faces_removed),
            ("holes closed", self.holes_closed),
            ("  faces added to close them", self.hole_faces_added),
            ("faces flipped for coherent orientation", self.faces_flipped_coherent),
            ("components flipped to face outward", self.components_flipped_outward),
            ("  faces flipped with them", self.faces_flipped_outward),
            ("unreferenced vertices removed", self.unreferenced_vertices_removed),
            ("normal smoothing iterations", self.normal_smoothing_iterations),
        ]
        width = max(len(name) for name, _ in rows)
        lines = ["repair" + " " * (width - 6) + "  count"]
        lines += [f"{name:<{width}}  {value:>5d}" for name, value in rows]
        if self.non_orientable_components:
            lines.append(f"{'non-orientable components (left as is)':<{width}}  {self.non_orientable_components:>5d}")
        before, after = self.before.as_dict(), self.after.as_dict()
        labels = {
            "vertices": "vertices",
            "triangles": "triangles",
            "duplicate_vertices": "duplicate vertices",
            "unreferenced_vertices": "unreferenced vertices",
            "null_faces": "null faces",
            "duplicate_faces": "duplicate faces",
            "zero_area_faces": "zero-area faces",
            "non_manifold_edges": "non-manifold edges",
            "non_manifold_vertices": "non-manifold vertices",
            "boundary_edges": "boundary edges",
            "boundary_loops": "boundary loops (holes, borders)",
            "largest_boundary_loop": "largest boundary loop (edges)",
            "components": "components",
            "inconsistent_edges": "inconsistently oriented edges",
        }
        width2 = max(len(v) for v in labels.values())
        lines += ["", f"{'mesh':<{width2}}  {'before':>9}  {'after':>9}"]
        lines += [f"{labels[key]:<{width2}}  {before[key]:>9d}  {after[key]:>9d}" for key in labels]
        lines.append(f"repair took {self.seconds:.2f} s")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()


def clean_mesh(
    mesh,
    *,
    unit=None,
    merge_duplicate_vertices: bool = True,
    remove_degenerate_faces: bool = True,
    repair_non_manifold: bool = True,
    min_island_fraction: float = 0.01,
    max_hole_edges: int = 100,
    orient_outward: bool = True,
    smooth_normals: int = 0,
) -> tuple[TriangleMesh, CleanReport]:
    """Repair a scanned mesh and report what changed.

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData
        The scan (a TriangleMesh: points in mm; a PolyData: in ``unit``, see
        :func:`~translucency.io.polydata.as_triangle_mesh`); it is not modified.
    unit : {"mm", "cm", "m", "in"} or float, optional
        A PolyData's length unit (None: its ``field_data["length_unit"]``, else inferred from the size).
    merge_duplicate_vertices : bool, default True
        Merge vertices at exactly the same position.
    remove_degenerate_faces : bool, default True
        Remove null (repeated index), duplicate and zero-area triangles.
    repair_non_manifold : bool, default True
        Make every edge and vertex manifold (required for closing holes).
    min_island_fraction : float, default 0.01
        Remove connected components whose area is below this fraction of the largest component's
        area (0 keeps everything).
    max_hole_edges : int, default 100
        Close the boundary loops of at most this many edges (0 closes none). Outer borders of open
        scans are loops too: keep this below their length to leave them open.
    orient_outward : bool, default True
        Make the orientation coherent and the normals point outward (see
        :mod:`translucency.geometry.orientation`).
    smooth_normals : int, default 0
        Iterations of light normal smoothing (each averages a vertex normal with its neighbours'
        and renormalises); 0 keeps the plain area-weighted normals.

    Returns
    -------
    mesh : TriangleMesh
        The repaired mesh, with ``point_data["normals"]`` set to its vertex normals.
    report : CleanReport
        Counts of what changed; ``str(report)`` is a readable table.

    Raises
    ------
    MeshError
        When nothing is left of the mesh, or pymeshlab fails on it.
    InvalidParameterError
        For out-of-range options.
    """
    mesh = as_triangle_mesh(mesh, unit, entry="clean_mesh")
    options = (merge_duplicate_vertices, remove_degenerate_faces, repair_non_manifold, min_island_fraction)
    options += (max_hole_edges, orient_outward, smooth_normals)
    points, triangles, origin, normals, report, measures = _clean(mesh.points, mesh.triangles, options)
    point_data = {name: np.asarray(values)[origin] for name, values in mesh.point_data.items() if name != "normals"}
    point_data["normals"] = normals
    for array in (triangles, normals, measures["vertex_areas"]):
        if array.base is None and array is not mesh.triangles:
            array.flags.writeable = False  # the cleaning's own: the mesh takes them without a copy
    cleaned = mesh.replace(points=points, triangles=triangles, point_data=point_data)
    if report.settings["smooth_normals"] == 0:
        measures["vertex_normals"] = cleaned.point_data["normals"]
    cleaned.remember(**measures)
    return cleaned, report


def clean_arrays(
    points,
    triangles,
    *,
    merge_duplicate_vertices: bool = True,
    remove_degenerate_faces: bool = True,
    repair_non_manifold: bool = True,
    min_island_fraction: float = 0.01,
    max_hole_edges: int = 100,
    orient_outward: bool = True,
    smooth_normals: int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, CleanReport]:
    """Array-level form of :func:`clean_mesh`.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions in mm.
    triangles : array_like of int, shape (m, 3)
    **options
        As for :func:`clean_mesh`.

    Returns
    -------
    points : ndarray, shape (k, 3), float64
    triangles : ndarray, shape (l, 3), int64
    origin : ndarray, shape (k,), int64
        For each output vertex, the input vertex it comes from (to carry per-vertex data over).
    normals : ndarray, shape (k, 3), float64
        Unit vertex normals of the result (smoothed when asked).
    report : CleanReport
    """
    options = (merge_duplicate_vertices, remove_degenerate_faces, repair_non_manifold, min_island_fraction)
    options += (max_hole_edges, orient_outward, smooth_normals)
    return _clean(points, triangles, options)[:5]


def _clean(points, triangles, options: tuple):
    """:func:`clean_arrays` with its options in their order, and the measures of the result taken on the way:
    ``{"vertex_areas", "surface_area", "mean_edge_length"}`` (barycentric vertex areas, mm²; total area, mm²; mean
    unique-edge length, mm, or None)."""
    started = time.perf_counter()
    points, triangles = validate_mesh_arrays(points, triangles)
    settings = _clean_settings(*options)
    survey = survey_mesh(points, triangles)
    before = survey.defects
    repair = _Repair(
        points, triangles, np.arange(len(points), dtype=np.int64), points, triangles, components=survey.components
    )
    if settings["merge_duplicate_vertices"]:
        _merge_vertices(repair, before)  # 1
    if settings["remove_degenerate_faces"]:
        _remove_null_and_duplicate_faces(repair, before)  # 2-3
    if settings["repair_non_manifold"]:
        _make_manifold(repair, before)  # 5-6
    if settings["remove_degenerate_faces"]:
        _remove_zero_area_faces(repair, before)  # 4, after 5-6: collapsing them needs a manifold mesh
    if settings["min_island_fraction"] > 0:
        _remove_small_islands(repair, before, settings["min_island_fraction"])  # 7
    if settings["orient_outward"]:
        _orient_coherently(repair, before)  # 8 (hole filling follows the orientation of the border)
    if settings["max_hole_edges"] > 0:
        _fill_holes(repair, before, settings["max_hole_edges"], settings["remove_degenerate_faces"])  # 9
    if settings["orient_outward"]:
        _orient_outward(repair)  # 10
    # no step removed, added or reconnected a face (flips at most): the same edges and vertices in use
    same_faces = repair.points is repair.input_points and len(repair.triangles) == len(repair.input_triangles)
    _remove_unreferenced_vertices(repair, before if same_faces else None)  # 11
    plain, vertex_areas, surface_area = vertex_measures(repair.points, repair.triangles)
    normals = _smoothed(plain, repair.triangles, settings["smooth_normals"])  # 12
    repair.counts["normal_smoothing_iterations"] = settings["smooth_normals"]

    points, triangles, origin = repair.points, repair.triangles, repair.origin
    unchanged = points.shape == repair.input_points.shape and (
        triangles is repair.input_triangles or np.array_equal(triangles, repair.input_triangles)
    )
    mean_edge = survey.mean_edge_length if same_faces else None  # flips and unused vertices leave the edges
    if not unchanged:
        after_survey = survey_mesh(points, triangles, lengths=mean_edge is None)
        after, mean_edge = after_survey.defects, mean_edge if mean_edge is not None else after_survey.mean_edge_length
    else:
        after = before
    report = CleanReport(
        before=before,
        after=after,
        non_orientable_components=int(repair.non_orientable),
        settings=settings,
        seconds=time.perf_counter() - started,
        **repair.counts,
    )
    measures = dict(vertex_areas=vertex_areas, surface_area=surface_area, mean_edge_length=mean_edge)
    return points, triangles, origin, normals, report, measures


def smooth_vertex_normals(points, triangles, iterations: int = 1) -> np.ndarray:
    """Area-weighted vertex normals, lightly smoothed over the one-ring.

    Each iteration replaces a vertex normal by the normalised sum of its own and its edge
    neighbours' normals (equal weights).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions in mm.
    triangles : array_like of int, shape (m, 3)
    iterations : int, default 1
        0 returns the plain area-weighted normals.

    Returns
    -------
    ndarray, shape (n, 3), float64
        Unit normals (zero for vertices without triangles).
    """
    return _smoothed(vertex_normals(points, triangles), triangles, iterations)


def _smoothed(normals, triangles, iterations):
    """:func:`smooth_vertex_normals` from the plain normals."""
    from scipy import sparse

    if iterations <= 0:
        return normals
    n = len(normals)
    edges, _ = unique_edges(triangles)
    adjacency = sparse.coo_matrix(
        (np.ones(2 * len(edges)), (np.r_[edges[:, 0], edges[:, 1]], np.r_[edges[:, 1], edges[:, 0]])), shape=(n, n)
    ).tocsr()
    adjacency = adjacency + sparse.identity(n, format="csr")
    for _ in range(iterations):
        summed = adjacency @ normals
        length = np.linalg.norm(summed, axis=1, keepdims=True)
        normals = np.divide(summed, length, out=np.zeros_like(summed), where=length > 0)
    return normals


# --------------------------------------------------------------------------------------------------
# The steps of clean_arrays, in the order it runs them (module docstring's table).


def _clean_settings(
    merge_duplicate_vertices,
    remove_degenerate_faces,
    repair_non_manifold,
    min_island_fraction,
    max_hole_edges,
    orient_outward,
    smooth_normals,
) -> dict:
    """The options of :func:`clean_arrays`, checked, as the report records them."""
    min_island_fraction = float(min_island_fraction)
    if not (0.0 <= min_island_fraction < 1.0):
        raise InvalidParameterError(
            f"min_island_fraction is {min_island_fraction}; pass a fraction in [0, 1), e.g. 0.01."
        )
    if int(max_hole_edges) != max_hole_edges or max_hole_edges < 0:
        raise InvalidParameterError(
            f"max_hole_edges is {max_hole_edges!r}; pass a whole number of edges >= 0, e.g. 100."
        )
    if int(smooth_normals) != smooth_normals or smooth_normals < 0:
        raise InvalidParameterError(f"smooth_normals is {smooth_normals!r}; pass a number of iterations >= 0.")
    return dict(
        merge_duplicate_vertices=bool(merge_duplicate_vertices),
        remove_degenerate_faces=bool(remove_degenerate_faces),
        repair_non_manifold=bool(repair_non_manifold),
        min_island_fraction=min_island_fraction,
        max_hole_edges=int(max_hole_edges),
        orient_outward=bool(orient_outward),
        smooth_normals=int(smooth_normals),
    )


@dataclasses.dataclass
class _Repair:
    """The mesh as the repair steps leave it, with what they counted.

    ``origin`` is, for each current vertex, the input vertex it comes from; ``counts`` become the
    :class:`CleanReport`'s fields; ``non_orientable`` the components no flip makes coherent;
    ``components`` the input faces' components found with the defects (or None).
    """

    points: np.ndarray
    triangles: np.ndarray
    origin: np.ndarray
    input_points: np.ndarray
    input_triangles: np.ndarray
    counts: dict = dataclasses.field(default_factory=dict)
    non_orientable: int = 0
    components: tuple | None = None

    def pristine(self) -> bool:
        """Whether the arrays are still the input's: then the defects found before tell which steps find nothing."""
        return self.points is self.input_points and self.triangles is self.input_triangles

    def known_components(self):
        """The components found with the defects while no step has changed which faces there are, else None: a
        step that removes, adds or reconnects faces replaces the points or changes their count; flips keep them."""
        same_faces = self.points is self.input_points and len(self.triangles) == len(self.input_triangles)
        return self.components if same_faces else None

    def replace(self, points, triangles, origin) -> None:
        """Take the arrays a step returns."""
        self.points, self.triangles, self.origin = points, triangles, origin


def _merge_vertices(repair: _Repair, before: MeshDefects) -> None:
    """Step 1: merge vertices at exactly the same position."""
    if not before.duplicate_vertices:
        repair.counts["duplicate_vertices_merged"] = 0
        return
    points, triangles, origin, merged = _merge_duplicate_vertices(repair.points, repair.triangles, repair.origin)
    repair.replace(points, triangles, origin)
    repair.counts["duplicate_vertices_merged"] = merged


def _remove_null_and_duplicate_faces(repair: _Repair, before: MeshDefects) -> None:
    """Steps 2-3: remove triangles with a repeated index, then those on the same vertices as an earlier one."""
    counts = repair.counts
    if repair.pristine() and before.null_faces == 0 and before.duplicate_faces == 0:
        counts["null_faces_removed"] = counts["duplicate_faces_removed"] = 0
        return
    triangles = repair.triangles
    null = (
        (triangles[:, 0] == triangles[:, 1])
        | (triangles[:, 1] == triangles[:, 2])
        | (triangles[:, 0] == triangles[:, 2])
    )
    triangles = triangles[~null]
    counts["null_faces_removed"] = int(np.count_nonzero(null))
    duplicate = duplicate_triangles(triangles)
    counts["duplicate_faces_removed"] = int(np.count_nonzero(duplicate))
    repair.triangles = triangles[~duplicate]
    _require_triangles(repair.triangles, "removing degenerate faces")


def _make_manifold(repair: _Repair, before: MeshDefects) -> None:
    """Steps 5-6: repair non-manifold edges and vertices (pymeshlab)."""
    if repair.pristine() and before.non_manifold_edges == 0 and before.non_manifold_vertices == 0:
        return
    repair.replace(
        *_repair_non_manifold(repair.points, repair.triangles, repair.origin, repair.input_points, repair.counts)
    )


def _remove_zero_area_faces(repair: _Repair, before: MeshDefects) -> None:
    """Step 4: collapse or remove triangles with collinear corners."""
    if repair.pristine() and before.zero_area_faces == 0:
        return
    zero = zero_area_mask(repair.points, repair.triangles)
    if zero.any():
        repair.replace(
            *_repair_zero_area_faces(repair.points, repair.triangles, repair.origin, repair.input_points, zero)
        )
        repair.counts["zero_area_faces_removed"] = int(np.count_nonzero(zero))
        _require_triangles(repair.triangles, "removing zero-area faces")


def _remove_small_islands(repair: _Repair, before: MeshDefects, min_island_fraction: float) -> None:
    """Step 7: remove components with less than ``min_island_fraction`` of the largest one's area."""
    if repair.pristine() and before.components <= 1:
        return
    count, component = repair.known_components() or face_components(repair.triangles)
    if count > 1:
        area = np.bincount(component, weights=triangle_areas(repair.points, repair.triangles), minlength=count)
        small = area < min_island_fraction * area.max()
        repair.counts["islands_removed"] = int(np.count_nonzero(small))
        keep = ~small[component]
        repair.counts["island_faces_removed"] = int(np.count_nonzero(~keep))
        repair.triangles = repair.triangles[keep]


def _orient_coherently(repair: _Repair, before: MeshDefects) -> None:
    """Step 8: flip triangles so that every edge runs both ways (:func:`coherent_orientation`)."""
    if repair.pristine() and before.inconsistent_edges == 0 and before.non_manifold_edges == 0:
        repair.counts["faces_flipped_coherent"] = 0  # every edge already runs both ways
        return
    flip, repair.non_orientable = coherent_orientation(repair.triangles)
    repair.triangles = flip_triangles(repair.triangles, flip)
    repair.counts["faces_flipped_coherent"] = int(np.count_nonzero(flip))


def _fill_holes(repair: _Repair, before: MeshDefects, max_hole_edges: int, remove_degenerate_faces: bool) -> None:
    """Step 9: close boundary loops of at most ``max_hole_edges`` edges (a patch over a border with
    collinear edges can hold zero-area faces: repaired too)."""
    if repair.pristine() and before.boundary_edges == 0:
        return
    faces_before = len(repair.triangles)
    repair.replace(
        *_close_holes(
            repair.points, repair.triangles, repair.origin, repair.input_points, int(max_hole_edges), repair.counts
        )
    )
    if remove_degenerate_faces and repair.counts.get("holes_closed", 0):
        zero = zero_area_mask(repair.points, repair.triangles)
        if zero.any():
            repair.replace(
                *_repair_zero_area_faces(repair.points, repair.triangles, repair.origin, repair.input_points, zero)
            )
    repair.counts["hole_faces_added"] = len(repair.triangles) - faces_before


def _orient_outward(repair: _Repair) -> None:
    """Step 10: coherent again (when holes were closed), then every component flipped to face outward."""
    counts = repair.counts
    if counts.get("holes_closed", 0):
        flip, repair.non_orientable = coherent_orientation(repair.triangles)
        repair.triangles = flip_triangles(repair.triangles, flip)
        counts["faces_flipped_coherent"] = counts.get("faces_flipped_coherent", 0) + int(np.count_nonzero(flip))
    flip, components_flipped = outward_flips(repair.points, repair.triangles, repair.known_components())
    if components_flipped:
        repair.triangles = flip_triangles(repair.triangles, flip)
    counts["components_flipped_outward"] = components_flipped
    counts["faces_flipped_outward"] = int(np.count_nonzero(flip))


def _remove_unreferenced_vertices(repair: _Repair, before: MeshDefects | None) -> None:
    """Step 11: drop the vertices no triangle uses (``before``: the input's defects, when the faces are still the
    input's and so use the same vertices)."""
    if before is not None and before.unreferenced_vertices == 0:
        repair.counts["unreferenced_vertices_removed"] = 0
        return
    used = np.zeros(len(repair.points), dtype=bool)
    used[repair.triangles.ravel()] = True
    repair.counts["unreferenced_vertices_removed"] = int(np.count_nonzero(~used))
    new_index = np.cumsum(used) - 1
    repair.replace(repair.points[used], new_index[repair.triangles], repair.origin[used])


# --------------------------------------------------------------------------------------------------
# Helpers of the steps.


def _require_triangles(triangles: np.ndarray, step: str) -> None:
    if len(triangles) == 0:
        raise MeshError(f"no triangle is left after {step}; the mesh is entirely degenerate, check the file.")


def _merge_duplicate_vertices(points, triangles, origin):
    """Merge vertices with identical coordinates; the first of each group stays."""
    representative = first_at_same_position(points)
    keep = representative == np.arange(len(points))
    merged = int(np.count_nonzero(~keep))
    if merged == 0:
        return points, triangles, origin, 0
    new_index = np.cumsum(keep) - 1
    return points[keep], new_index[representative[triangles]], origin[keep], merged


def _to_meshset(pymeshlab, points, triangles, origin):
    mesh = pymeshlab.Mesh(
        vertex_matrix=np.ascontiguousarray(points), face_matrix=np.ascontiguousarray(triangles, dtype=np.int32)
    )
    mesh.add_vertex_custom_scalar_attribute(origin.astype(np.float64) + 1.0, _ORIGIN)
    mesh_set = pymeshlab.MeshSet()
    mesh_set.add_mesh(mesh)
    return mesh_set


def _from_meshset(mesh_set, input_points):
    """Arrays back from pymeshlab; vertices pymeshlab created get the origin of the input vertex at their position."""
    mesh = mesh_set.current_mesh()
    mesh.compact()
    points = np.array(mesh.vertex_matrix(), dtype=np.float64).reshape(-1, 3)
    triangles = np.array(mesh.face_matrix(), dtype=np.int64).reshape(-1, 3)
    tag = np.array(mesh.vertex_custom_scalar_attribute_array(_ORIGIN))
    origin = np.rint(tag).astype(np.int64) - 1
    new = origin < 0
    if np.any(new):
        from scipy.spatial import cKDTree

        _, nearest = cKDTree(input_points).query(points[new])
        origin[new] = nearest
    return points, triangles, origin


def _non_manifold_counts(triangles: np.ndarray, n: int) -> tuple[int, int]:
    _, edge_of_corner = unique_edges(triangles)
    faces_per_edge = np.bincount(edge_of_corner.ravel())
    edges = int(np.count_nonzero(faces_per_edge > 2))
    vertices = count_non_manifold_vertices(triangles, edge_of_corner, faces_per_edge, n)
    return edges, vertices


def _repair_non_manifold(points, triangles, origin, input_points, counts):
    from .meshlab import import_pymeshlab

    bad_edges, bad_vertices = _non_manifold_counts(triangles, len(points))
    if bad_edges == 0 and bad_vertices == 0:
        return points, triangles, origin
    pymeshlab = import_pymeshlab()
    edges_found = faces_removed = vertices_found = vertices_added = 0
    for _ in range(4):  # pymeshlab's repair can expose a few new defects: repeat until none is left
        if bad_edges == 0 and bad_vertices == 0:
            break
        mesh_set = _to_meshset(pymeshlab, points, triangles, origin)
        try:
            if bad_edges:
                edges_found += bad_edges
                faces_before = mesh_set.current_mesh().face_number()
                mesh_set.meshing_repair_non_manifold_edges(method="Remove Faces")
                faces_removed += faces_before - mesh_set.current_mesh().face_number()
                mesh_set.meshing_remove_unreferenced_vertices()
                points, triangles, origin = _from_meshset(mesh_set, input_points)
                bad_vertices = _non_manifold_counts(triangles, len(points))[1]
                mesh_set = _to_meshset(pymeshlab, points, triangles, origin)
            if bad_vertices:
                vertices_found += bad_vertices
                vertices_before = mesh_set.current_mesh().vertex_number()
                mesh_set.meshing_repair_non_manifold_vertices(vertdispratio=_SPLIT_DISPLACEMENT)
                vertices_added += mesh_set.current_mesh().vertex_number() - vertices_before
        except pymeshlab.PyMeshLabException as exc:
            raise MeshError(
                f"pymeshlab could not repair the non-manifold parts of the mesh ({exc}); repair it in MeshLab first."
            ) from exc
        points, triangles, origin = _from_meshset(mesh_set, input_points)
        _require_triangles(triangles, "repairing non-manifold edges")
        bad_edges, bad_vertices = _non_manifold_counts(triangles, len(points))
    counts["non_manifold_edges_repaired"] = edges_found
    counts["non_manifold_edge_faces_removed"] = faces_removed
    counts["non_manifold_vertices_repaired"] = vertices_found
    counts["non_manifold_vertices_added"] = vertices_added
    return points, triangles, origin


def _is_manifold(triangles: np.ndarray, n: int) -> bool:
    return _non_manifold_counts(triangles, n) == (0, 0)


def _repair_zero_area_faces(points, triangles, origin, input_points, zero):
    """Collapse the short edge of zero-area triangles (pymeshlab), then remove any that are left.

    pymeshlab's ``meshing_remove_t_vertices`` with a base/height threshold of
    ``1 / ZERO_AREA_RATIO`` touches exactly the zero-area triangles of
    :func:`~translucency.io.defects.zero_area_mask`; collapsing instead of deleting them leaves no
    crack (deleting an interior zero-area triangle opens a zero-width hole whose filling would make
    the same triangle again). It needs a manifold mesh; the triangles it cannot fix are removed.
    """
    if _is_manifold(triangles, len(points)):
        from .meshlab import import_pymeshlab

        pymeshlab = import_pymeshlab()
        mesh_set = _to_meshset(pymeshlab, points, triangles, origin)
        try:
            mesh_set.meshing_remove_t_vertices(method="Edge Collapse", threshold=1.0 / ZERO_AREA_RATIO, repeat=True)
            mesh_set.meshing_remove_unreferenced_vertices()
            candidate = _from_meshset(mesh_set, input_points)
        except pymeshlab.PyMeshLabException:
            candidate = None
        if candidate is not None and len(candidate[1]) and _is_manifold(candidate[1], len(candidate[0])):
            points, triangles, origin = candidate
        zero = zero_area_mask(points, triangles)
    return points, triangles[~zero], origin


def _close_holes(points, triangles, origin, input_points, max_hole_edges, counts):
    from .meshlab import import_pymeshlab

    edges, edge_of_corner = unique_edges(triangles)
    faces_per_edge = np.bincount(edge_of_corner.ravel(), minlength=len(edges))
    if not np.any(faces_per_edge == 1):
        return points, triangles, origin
    if np.any(faces_per_edge > 2):
        raise MeshError(
            "holes cannot be closed in a mesh with non-manifold edges; keep repair_non_manifold=True or pass "
            "max_hole_edges=0."
        )
    pymeshlab = import_pymeshlab()
    mesh_set = _to_meshset(pymeshlab, points, triangles, origin)
    closed = 0
    try:
        # first refuse patches that would intersect the surface, then close what is left regardless
        for self_intersection_check in (True, False):
            result = mesh_set.meshing_close_holes(
                maxholesize=int(max_hole_edges), selfintersection=self_intersection_check, newfaceselected=False
            )
            closed += int((result or {}).get("closed_holes", 0))
    except pymeshlab.PyMeshLabException as exc:
        raise MeshError(
            f"pymeshlab could not close the holes of the mesh ({exc}); pass max_hole_edges=0 to skip it."
        ) from exc
    counts["holes_closed"] = closed
    return _from_meshset(mesh_set, input_points)
