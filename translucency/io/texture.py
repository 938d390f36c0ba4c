"""A mesh's texture image sampled at its vertices (per-vertex colour for scans that carry a texture).

A vertex on a texture seam has one texture coordinate per face corner; its colour is the mean of the
texture at each of them. The texture is sampled bilinearly with repeat wrapping, ``v`` measured from
the image's bottom row (the OBJ convention).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import MeshError
from .readable import check_pixels, image_size

__all__ = ["read_texture", "sample_at_vertices"]


def read_texture(path: Path) -> np.ndarray:
    """The image at ``path`` as an ``(h, w, 3)`` float64 array of 8-bit values (alpha dropped, grey expanded);
    a sentence naming the file when it cannot be read."""
    import warnings

    import imageio.v3 as iio

    size = image_size(path)
    if size is not None:  # 8-bit RGBA as read, and float64 RGB
        check_pixels(f"the texture {path.name}", *size, 4 + 24, MeshError, "resample it to at most 8192 x 8192 pixels")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # imageio's plugins warn while they try an unknown file
            image = np.asarray(iio.imread(path))
    except Exception:  # imageio raises many types, with its own words: the sentence has the file and what to do
        raise MeshError(
            f"the texture {path.name} could not be read as an image (damaged, or in a format no installed reader "
            "handles); check the file or save it as PNG."
        ) from None
    if image.ndim == 2:
        image = np.repeat(image[:, :, None], 3, axis=2)
    if image.ndim != 3 or image.shape[2] < 3:
        raise MeshError(f"the texture {path.name} is not an RGB image (shape {image.shape}); save it as RGB.")
    image = image[:, :, :3].astype(np.float64)
    if image.max(initial=0) > 255.0:  # 16-bit images
        image = image * (255.0 / 65535.0)
    return image


def sample_at_vertices(image: np.ndarray, corner_uv: np.ndarray, corner_vertex: np.ndarray, n_vertices: int):
    """Per-vertex ``(n, 3)`` uint8 colour: the mean over each vertex's corners of the image at their
    ``(u, v)`` coordinates, and a boolean mask of the vertices that had any corner.

    ``corner_uv`` is ``(k, 2)`` texture coordinates and ``corner_vertex`` ``(k,)`` the vertex of each.
    """
    h, w = image.shape[:2]
    x = np.mod(corner_uv[:, 0], 1.0) * w - 0.5
    y = (1.0 - np.mod(corner_uv[:, 1], 1.0)) * h - 0.5
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    x1, y1 = np.mod(x0 + 1, w), np.mod(y0 + 1, h)
    x0, y0 = np.mod(x0, w), np.mod(y0, h)
    texel = (
        image[y0, x0] * (1 - fx) * (1 - fy)
        + image[y0, x1] * fx * (1 - fy)
        + image[y1, x0] * (1 - fx) * fy
        + image[y1, x1] * fx * fy
    )
    total = np.zeros((n_vertices, 3))
    np.add.at(total, corner_vertex, texel)
    count = np.bincount(corner_vertex, minlength=n_vertices)
    has = count > 0
    total[has] /= count[has, None]
    return np.clip(np.round(total), 0, 255).astype(np.uint8), has
