"""HDR environment maps: equirectangular radiance images read from files.

Readers, by file extension:

* ``.hdr`` / ``.pic`` (Radiance RGBE): VTK's ``vtkHDRReader`` (VTK is already required through
  PyVista). imageio cannot read this format here: its only ``.hdr`` backends are FreeImage (a
  separately downloaded binary) and OpenCV, neither a dependency.
* ``.exr``, ``.tif`` / ``.tiff``, ``.pfm`` and other float images: imageio, when one of its
  installed backends can read the file (float TIFF works with the base install; EXR needs e.g.
  ``pip install imageio[opencv]``).
* ``.npy``: a float array of shape (H, W, 3) saved with NumPy.

Pixel values are taken as linear radiance in W/(m² sr) (scale them with ``scale`` if the map is in
another unit). The axes of the image are those of
:class:`translucency.scatter.lights.EnvironmentLight`: row 0 is the zenith, columns run with the
azimuth. This module returns arrays; :func:`translucency.app.environment.load_environment` builds the
light from them (``io`` and ``scatter`` do not import each other).

========= ====================================================== =========
name      meaning                                                unit
========= ====================================================== =========
L         radiance of one pixel, linear RGB                      W/(m² sr)
H, W      image height (polar angle) and width (azimuth)         pixels
========= ====================================================== =========
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import TranslucencyError
from .readable import check_pixels, image_size, regular_file

__all__ = ["EnvironmentMapError", "read_equirectangular", "RADIANCE_EXTENSIONS"]

RADIANCE_EXTENSIONS = (".hdr", ".pic")
IMPLAUSIBLE_RADIANCE = 1e30  # RGBE goes up to ~1.7e38; anything this large is a decoding failure
#: Bytes a decoded pixel takes while it is read: the reader's float32 RGB, and two float64 RGB copies.
DECODED_PIXEL_BYTES = 3 * (4 + 8 + 8)
_RADIANCE_RESOLUTION = re.compile(rb"^[-+][XY] +(\d+) +[-+][XY] +(\d+)$")


class EnvironmentMapError(TranslucencyError, ValueError):
    """An environment map file that cannot be read or is not a radiance image."""


def check_pixel_count(name: str, height: int, width: int) -> None:
    """Refuse a map whose header claims too many pixels to decode (:func:`~translucency.io.readable.check_pixels`)."""
    check_pixels(
        name, height, width, DECODED_PIXEL_BYTES, EnvironmentMapError, "resample the map to at most 4096 x 2048 pixels"
    )


def _radiance_size(path: Path) -> tuple[int, int] | None:
    """``(height, width)`` from a Radiance file's header (the resolution line after the first empty line), or
    None when the header cannot be read that way (the reader then decides)."""
    with open(path, "rb") as stream:
        head = stream.read(65536)
    lines = head.split(b"\n")
    for at, line in enumerate(lines[:-1]):
        if not line.strip():
            match = _RADIANCE_RESOLUTION.match(lines[at + 1].strip())
            if match is None:
                return None
            first, second = int(match.group(1)), int(match.group(2))
            return (first, second) if lines[at + 1].strip()[1:2] == b"Y" else (second, first)
    return None


def _npy_shape(path: Path) -> tuple:
    """The array shape a NumPy ``.npy`` file's header declares, read without its data."""
    with open(path, "rb") as stream:
        version = np.lib.format.read_magic(stream)
        read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        return read(stream)[0]


def _read_radiance_hdr(path: Path) -> np.ndarray:
    """Radiance RGBE file through VTK, as (H, W, 3) float64 with row 0 at the top of the image."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOImage import vtkHDRReader

    size = _radiance_size(path)
    if size is not None:
        check_pixel_count(path.name, *size)

    reader = vtkHDRReader()
    if not reader.CanReadFile(str(path)):
        raise EnvironmentMapError(f"{path.name} is not a Radiance HDR (RGBE) file; check the file or its extension.")
    errors = []
    reader.AddObserver("ErrorEvent", lambda obj, event: errors.append(event))  # keeps VTK quiet, we report
    reader.SetFileName(str(path))
    reader.Update()
    image = reader.GetOutput()
    scalars = image.GetPointData().GetScalars() if image is not None else None
    if errors or scalars is None:
        raise EnvironmentMapError(
            f"{path.name} could not be decoded as a Radiance HDR image (damaged or truncated file)."
        )
    width, height, _ = image.GetDimensions()
    pixels = vtk_to_numpy(scalars).astype(np.float64)
    if pixels.shape != (width * height, 3):
        raise EnvironmentMapError(f"{path.name}: expected an RGB image, got {pixels.shape[-1]} channels per pixel.")
    return pixels.reshape(height, width, 3)[::-1]  # VTK stores the bottom row first


def _read_with_imageio(path: Path) -> np.ndarray:
    import imageio.v3 as iio

    size = image_size(path)
    if size is not None:
        check_pixel_count(path.name, *size)
    try:
        pixels = iio.imread(path)
    except Exception:  # imageio raises OSError, ValueError or a plugin's own error
        raise EnvironmentMapError(
            f"{path.name} cannot be read as an image: no installed reader handles "
            f"{repr(path.suffix) + ' files' if path.suffix else 'files without an extension'}; convert the map to "
            "Radiance .hdr, or install a backend imageio can use for it (e.g. 'pip install imageio[opencv]' for .exr)."
        ) from None
    pixels = np.asarray(pixels)
    if not np.issubdtype(pixels.dtype, np.floating):
        raise EnvironmentMapError(
            f"{path.name} holds {pixels.dtype} pixels, a display image, not radiance; "
            "use a floating-point HDR map (.hdr, .exr, float TIFF)."
        )
    return pixels


def read_equirectangular(path) -> np.ndarray:
    """Read an equirectangular environment map as linear radiance.

    Parameters
    ----------
    path : str or os.PathLike
        ``.hdr``/``.pic`` (Radiance), ``.npy``, or a float image imageio can read (module docstring).

    Returns
    -------
    ndarray, shape (H, W, 3), float64
        Radiance per pixel, row 0 at the top (zenith). Grey images are repeated over RGB and an
        alpha channel is dropped.

    Raises
    ------
    EnvironmentMapError
        With a sentence, for a missing, unreadable, non-float or non-radiance file.
    """
    path = regular_file(path, EnvironmentMapError, "environment map", "image file")
    suffix = path.suffix.lower()
    if suffix in RADIANCE_EXTENSIONS:
        pixels = _read_radiance_hdr(path)
    elif suffix == ".npy":
        unreadable = EnvironmentMapError(
            f"{path.name} is not a NumPy array file of numbers; save the map with numpy.save as an (H, W, 3) "
            "float array."
        )
        try:
            shape = _npy_shape(path)
        except (OSError, ValueError, EOFError):
            raise unreadable from None
        if len(shape) >= 2:
            check_pixel_count(path.name, int(shape[0]), int(shape[1]))
        try:
            pixels = np.load(path, allow_pickle=False)
        except (OSError, ValueError, EOFError):
            raise unreadable from None
    else:
        pixels = _read_with_imageio(path)
    pixels = np.asarray(pixels, dtype=np.float64)
    if pixels.ndim == 2:
        pixels = np.repeat(pixels[:, :, None], 3, axis=2)
    if pixels.ndim != 3 or pixels.shape[2] not in (1, 3, 4):
        raise EnvironmentMapError(
            f"{path.name}: an environment map must be an (H, W, 3) RGB image, got shape {pixels.shape}."
        )
    if pixels.shape[2] == 1:
        pixels = np.repeat(pixels, 3, axis=2)
    pixels = np.ascontiguousarray(pixels[:, :, :3])
    if pixels.shape[0] < 1 or pixels.shape[1] < 1:
        raise EnvironmentMapError(f"{path.name} is an empty image.")
    if not np.all(np.isfinite(pixels)) or pixels.max() >= IMPLAUSIBLE_RADIANCE:
        raise EnvironmentMapError(f"{path.name} decodes to NaN, infinite or absurd values; the file is damaged.")
    if pixels.min() < 0:
        raise EnvironmentMapError(f"{path.name} has negative pixels (min {pixels.min():g}); radiance must be >= 0.")
    return pixels
