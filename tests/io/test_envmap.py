"""Environment maps: Radiance HDR round trip, orientation, other formats, errors with sentences."""

import numpy as np
import pytest

from translucency.app.environment import load_environment
from translucency.errors import TranslucencyError
from translucency.io.envmap import EnvironmentMapError, read_equirectangular
from translucency.scatter.lights import EnvironmentLight


def write_radiance_hdr(path, image):
    """Write linear RGB (H, W, 3) as a Radiance RGBE file with run-length-encoded scanlines."""
    image = np.asarray(image, dtype=np.float64)
    height, width, _ = image.shape
    brightest = image.max(axis=2)
    mantissa, exponent = np.frexp(brightest)  # brightest = mantissa * 2**exponent, mantissa in [0.5, 1)
    positive = brightest > 1e-32
    scale = np.where(positive, mantissa * 256.0 / np.where(positive, brightest, 1.0), 0.0)
    rgbe = np.zeros((height, width, 4), dtype=np.uint8)
    rgbe[..., :3] = np.clip(image * scale[..., None], 0, 255).astype(np.uint8)
    rgbe[..., 3] = np.where(positive, exponent + 128, 0).astype(np.uint8)
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {height} +X {width}\n".encode())
    for row in rgbe:
        out += bytes([2, 2, width >> 8, width & 255])
        for channel in range(4):  # each channel as literal runs of at most 128 bytes
            data = row[:, channel].tobytes()
            for start in range(0, width, 128):
                part = data[start : start + 128]
                out += bytes([len(part)]) + part
    path.write_bytes(bytes(out))


def test_radiance_hdr_round_trip_keeps_values_and_orientation(tmp_path):
    rng = np.random.default_rng(0)
    image = rng.random((32, 64, 3)) * np.array([1.0, 10.0, 100.0])
    image[0, :] = (500.0, 400.0, 300.0)  # a bright top row: must come back as row 0 (the zenith)
    write_radiance_hdr(tmp_path / "sky.hdr", image)
    pixels = read_equirectangular(tmp_path / "sky.hdr")
    assert pixels.shape == (32, 64, 3) and pixels.dtype == np.float64
    # RGBE keeps 8 mantissa bits of the brightest channel of each pixel.
    assert np.all(np.abs(pixels - image) <= image.max(axis=2, keepdims=True) / 128.0)
    assert np.allclose(pixels[0], (500.0, 400.0, 300.0), rtol=1 / 128)


def test_load_environment_builds_a_sampled_light(tmp_path):
    image = np.full((32, 64, 3), 0.25)
    write_radiance_hdr(tmp_path / "grey.hdr", image)
    light = load_environment(tmp_path / "grey.hdr", n_directions=128, scale=4.0)
    assert isinstance(light, EnvironmentLight) and light.name == "grey.hdr" and light.sampling == "importance"
    assert np.allclose(light.radiance_map, 1.0)
    samples = light.directional_samples()
    assert np.allclose(samples.irradiance_rgb.sum(axis=0), 4 * np.pi, rtol=1e-12)


@pytest.mark.filterwarnings("ignore:ImageIO.s vendored tifffile:DeprecationWarning")
def test_numpy_and_float_tiff_maps(tmp_path):
    image = np.random.default_rng(1).random((8, 16, 3))
    np.save(tmp_path / "map.npy", image)
    assert np.array_equal(read_equirectangular(tmp_path / "map.npy"), image)
    np.save(tmp_path / "grey.npy", image[..., 0])
    assert np.array_equal(read_equirectangular(tmp_path / "grey.npy")[..., 2], image[..., 0])
    iio = pytest.importorskip("imageio.v3")
    iio.imwrite(tmp_path / "map.tif", image.astype(np.float32))
    assert np.allclose(read_equirectangular(tmp_path / "map.tif"), image, rtol=1e-6)


def test_unreadable_files_give_a_sentence(tmp_path):
    with pytest.raises(EnvironmentMapError, match="does not exist"):
        read_equirectangular(tmp_path / "missing.hdr")
    (tmp_path / "text.hdr").write_text("not an image")
    with pytest.raises(EnvironmentMapError, match="not a Radiance HDR"):
        read_equirectangular(tmp_path / "text.hdr")
    (tmp_path / "cut.hdr").write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 40 +X 64\n" + b"\x02\x02\x00\x40" * 3)
    with pytest.raises(EnvironmentMapError, match="could not be decoded"):
        read_equirectangular(tmp_path / "cut.hdr")
    (tmp_path / "noise.xyz").write_bytes(b"\x00\x01\x02")
    with pytest.raises(EnvironmentMapError, match="no installed reader handles '.xyz' files"):
        read_equirectangular(tmp_path / "noise.xyz")
    with pytest.raises(TranslucencyError):  # the CLI prints these without a traceback
        read_equirectangular(tmp_path / "noise.xyz")


def test_display_images_and_bad_arrays_are_rejected(tmp_path):
    iio = pytest.importorskip("imageio.v3")
    iio.imwrite(tmp_path / "photo.png", np.zeros((4, 8, 3), dtype=np.uint8))
    with pytest.raises(EnvironmentMapError, match="display image, not radiance"):
        read_equirectangular(tmp_path / "photo.png")
    np.save(tmp_path / "negative.npy", -np.ones((4, 8, 3)))
    with pytest.raises(EnvironmentMapError, match="negative pixels"):
        read_equirectangular(tmp_path / "negative.npy")
    np.save(tmp_path / "cube.npy", np.ones((2, 4, 8, 3)))
    with pytest.raises(EnvironmentMapError, match=r"\(H, W, 3\) RGB image"):
        read_equirectangular(tmp_path / "cube.npy")
    with pytest.raises(EnvironmentMapError, match="scale"):
        load_environment(tmp_path / "negative.npy", scale=-1.0)


def test_a_header_that_claims_too_many_pixels_is_refused_before_decoding(tmp_path):
    """A decompression bomb: a few bytes whose header claims 1e10 pixels (600 GB decoded) would abort the process
    inside the reader; it is refused from the header, in one sentence naming the size."""
    (tmp_path / "bomb.hdr").write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n" + bytes(64))
    with pytest.raises(EnvironmentMapError, match=r"claims 100000 x 100000 pixels, 600\.0 GB to decode.*resample"):
        read_equirectangular(tmp_path / "bomb.hdr")
    with open(tmp_path / "bomb.npy", "wb") as stream:  # a NumPy header claiming 2**30 pixels, and 16 bytes of data
        np.lib.format.write_array_header_1_0(
            stream, {"descr": "<f4", "fortran_order": False, "shape": (32768, 32768, 3)}
        )
        stream.write(bytes(16))
    with pytest.raises(EnvironmentMapError, match=r"claims 32768 x 32768 pixels"):
        read_equirectangular(tmp_path / "bomb.npy")


def test_a_fifo_or_a_folder_is_refused_without_opening_it(tmp_path, fifo):
    with pytest.raises(EnvironmentMapError, match=r"is a FIFO \(named pipe\), not a regular file; pass an image file"):
        read_equirectangular(fifo("sky.hdr"))
    with pytest.raises(EnvironmentMapError, match="is a directory, not an image file"):
        read_equirectangular(tmp_path)
