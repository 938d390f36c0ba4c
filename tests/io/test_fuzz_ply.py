"""Fuzzing the PLY loader: mutated valid files (bit flips, truncation, inserted and deleted bytes, header
edits) either load as a finite, valid mesh or raise TranslucencyError -- never another exception, never
a hang, and the file is never written to.

Bounded: ``max_examples`` examples, derandomised, and no new work once ``BUDGET_S`` seconds have passed.
"""

import re
import signal
import time
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from translucency.errors import TranslucencyError
from translucency.io import load_mesh

from .conftest import icosphere
from .test_broken_files import binary_ply
from .test_load import write_ply

BUDGET_S = 10.0  # seconds of fuzzing per encoding (ascii, binary)
HANG_S = 60  # one load taking longer than this is a hang (a tiny file loads in milliseconds)
POINTS, TRIANGLES = icosphere(1, 20.0)
HEADER_NUMBERS = [0, 1, 2, 3, 4, 255, 256, 65535, 2**31 - 1, 2**32, 10**12, -1]
BODY_TOKENS = [b"300", b"256", b"0", b"-1", b"2147483648", b"4", b"nan", b"inf", b"-inf", b"1e39", b"3.5", b"x", b""]
HEADER_WORDS = [
    b"float",
    b"double",
    b"uchar",
    b"int",
    b"uint",
    b"char",
    b"short",
    b"int64",
    b"list",
    b"vertex",
    b"face",
    b"tristrips",
    b"x",
    b"ascii",
    b"binary_little_endian",
    b"binary_big_endian",
    b"property",
    b"element",
    b"end_header",
    b"comment",
    b"\n",
    b" ",
    b"\r\n",
]


@pytest.fixture(scope="module")
def seeds(tmp_path_factory):
    """Valid PLY files by encoding: ascii and binary (both byte orders; the loader's little-endian fast
    path), triangles with colours and a float property, quads and polygons, triangle strips."""
    folder = tmp_path_factory.mktemp("seeds")
    colors = np.clip((POINTS / 20 + 1) * 127.5, 0, 255).astype(np.uint8)
    confidence = np.linspace(0, 1, len(POINTS)).astype(np.float32)
    polygons = [list(t) + [t[0]] for t in TRIANGLES[:10]] + [list(t) for t in TRIANGLES[10:]]
    files = {"ascii": [], "binary": [binary_ply(POINTS, TRIANGLES)]}
    for k, (text, order) in enumerate([(True, "="), (False, "<"), (False, ">")]):
        path = folder / f"{k}.ply"
        kind = "ascii" if text else "binary"
        write_ply(
            path,
            POINTS,
            [list(t) for t in TRIANGLES],
            text=text,
            byte_order=order,
            colors=colors,
            extra={"confidence": confidence},
        )
        files[kind].append(path.read_bytes())
        write_ply(path, POINTS, polygons, text=text, byte_order=order)
        files[kind].append(path.read_bytes())
        write_ply(path, POINTS, None, text=text, byte_order=order, strips=[0, 1, 2, 3, 4, 5, 6, 7, -1, 8, 9, 10, 11])
        files[kind].append(path.read_bytes())
    return files


positions = st.floats(0.0, 1.0, exclude_max=True)
mutations = st.one_of(
    st.tuples(st.just("flip"), positions, st.integers(0, 7)),
    st.tuples(st.just("flip_header"), positions, st.integers(0, 7)),
    st.tuples(st.just("truncate"), positions),
    st.tuples(st.just("insert"), positions, st.binary(min_size=1, max_size=8)),
    st.tuples(st.just("delete"), positions, st.integers(1, 16)),
    st.tuples(st.just("header_number"), st.integers(0, 30), st.sampled_from(HEADER_NUMBERS)),
    st.tuples(st.just("header_word"), positions, st.sampled_from(HEADER_WORDS), st.integers(0, 8)),
    st.tuples(st.just("body_token"), positions, st.sampled_from(BODY_TOKENS)),  # any ascii value or index
    st.tuples(st.just("line_start"), positions, st.sampled_from(BODY_TOKENS)),  # an x coordinate or a list length
)


def mutate(data: bytes, operations) -> bytes:
    """Apply the mutations in order; positions are fractions of the current length (of the header for
    the header edits, of the whitespace-separated tokens or of the lines after the header for the body edits)."""
    data = bytearray(data)
    for op, *args in operations:
        end = data.find(b"end_header")
        header = end if end > 0 else len(data)
        if op in ("flip", "flip_header") and data:
            at = int(args[0] * (header if op == "flip_header" else len(data)))
            data[at] ^= 1 << args[1]
        elif op == "truncate":
            del data[int(args[0] * len(data)) :]
        elif op == "insert":
            at = int(args[0] * (len(data) + 1))
            data[at:at] = args[1]
        elif op == "delete" and data:
            at = int(args[0] * len(data))
            del data[at : at + args[1]]
        elif op == "header_number":
            numbers = list(re.finditer(rb"-?\d+", bytes(data[:header])))
            if numbers:
                m = numbers[args[0] % len(numbers)]
                data[m.start() : m.end()] = str(args[1]).encode()
        elif op == "header_word":
            at = int(args[0] * header)
            data[at : at + args[2]] = args[1]
        elif op in ("body_token", "line_start"):
            pattern = rb"\S+" if op == "body_token" else rb"(?m)^[ \t]*\S+"
            tokens = list(re.finditer(pattern, bytes(data[header:])))
            if tokens:
                m = tokens[int(args[0] * len(tokens))]
                data[header + m.start() : header + m.end()] = args[1]
    return bytes(data)


class _Hang(Exception):
    pass


def _raise_hang(signum, frame):
    raise _Hang()


_started = {}


@pytest.mark.parametrize("encoding", ["ascii", "binary"])
@settings(
    max_examples=150, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(which=st.integers(0, 63), operations=st.lists(mutations, min_size=1, max_size=3))
def test_mutated_ply_loads_or_raises_a_translucency_error(tmp_path, seeds, encoding, which, operations):
    started = _started.setdefault(encoding, time.monotonic())
    if time.monotonic() - started > BUDGET_S:
        return  # the budget is spent: the remaining examples do no work
    data = mutate(seeds[encoding][which % len(seeds[encoding])], operations)
    path = tmp_path / "fuzzed.ply"
    path.write_bytes(data)
    previous = signal.signal(signal.SIGALRM, _raise_hang)
    signal.alarm(HANG_S)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # implausible sizes of mutated coordinates
            mesh = load_mesh(path)
    except TranslucencyError as exc:
        text = str(exc)
        assert "fuzzed.ply" in text and "\n" not in text, text
        mesh = None
    except _Hang:
        pytest.fail(f"load_mesh did not return within {HANG_S} s on {data[:200]!r}")
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    assert path.read_bytes() == data  # reading never writes
    if mesh is not None:
        assert np.all(np.isfinite(mesh.points))
        assert mesh.n_triangles > 0 and mesh.triangles.min() >= 0 and mesh.triangles.max() < mesh.n_points
