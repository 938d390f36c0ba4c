"""Ground truth on a mesh: path-traced radiance to measure the scattering models against.

:mod:`translucency.reference.pathtrace` is the project's own unbiased random walk in a closed mesh with
Embree ray casts (docs/physics.md §9.5). Nothing here is imported by ``import translucency``; the
modules load on demand.

:mod:`translucency.reference.mitsuba_check` is the independent check of it: the same radiance along
the normal path-traced by Mitsuba 3's ``volpath`` (docs/physics.md §9.6; the ``reference`` extra),
Mitsuba imported only when its functions run.
"""
