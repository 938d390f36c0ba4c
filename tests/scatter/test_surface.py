"""The solver's surface is plain data; what an algorithm keeps per surface is that algorithm's, and goes with it."""

import dataclasses
import gc
import weakref

import numpy as np

from translucency.geometry.measure import vertex_normals
from translucency.geometry.synthetic import icosphere
from translucency.scatter import hierarchy, nearfield
from translucency.scatter.surface import PerSurface, SurfaceGeometry, held_bytes, ordered_bytes, spatial_order


def _sphere(level=2):
    points, triangles = icosphere(level, 5.0)
    return SurfaceGeometry(points, triangles, vertex_normals(points, triangles))


def test_the_surface_holds_its_fields_and_its_own_measures_only():
    surface = _sphere()
    hierarchy.tree_of(surface)
    nearfield.lists_of(surface, np.arange(surface.n_vertices), 2.0)
    fields = {f.name for f in dataclasses.fields(surface)}
    own = set(vars(surface)) - fields
    # the algorithms' work is not on it; its areas and edges are computed once, on it
    assert own <= {"triangle_areas", "vertex_areas", "mean_edge_length", "longest_edge"}


def test_what_an_algorithm_keeps_is_made_once_and_freed_with_the_surface():
    kept = PerSurface("test: made per surface")
    surface = _sphere()
    made = []
    first = kept.get(surface, "key", lambda: made.append(1) or np.zeros(1000))
    assert kept.get(surface, "key", lambda: made.append(1) or np.ones(3)) is first and made == [1]
    assert kept.peek(_sphere(), "key") is None  # another surface, even of the same shape, has its own
    watched = weakref.ref(first)
    del surface, first
    gc.collect()
    assert watched() is None


def test_the_tree_is_one_per_surface_and_leaf_size():
    surface = _sphere()
    assert hierarchy.tree_of(surface) is hierarchy.tree_of(surface)
    assert hierarchy.tree_of(surface, 2 * hierarchy.LEAF_SIZE) is not hierarchy.tree_of(surface)
    assert hierarchy.tree_of(_sphere()) is not hierarchy.tree_of(surface)


def test_the_budget_counts_what_the_algorithms_keep_for_the_ordered_surface():
    surface = _sphere(3)
    assert ordered_bytes(surface) == 0  # nothing ordered yet: nothing held
    ordered, order, rank = spatial_order(surface)
    bare = ordered_bytes(surface)
    assert bare >= ordered.points.nbytes + ordered.triangles.nbytes + ordered.normals.nbytes + order.nbytes
    tree = hierarchy.tree_of(ordered)
    assert ordered_bytes(surface) - bare >= tree.order.nbytes + tree.centre.nbytes
    assert held_bytes(ordered) == ordered_bytes(surface) - order.nbytes - rank.nbytes
    assert spatial_order(surface)[0] is ordered and spatial_order(ordered)[0] is ordered
