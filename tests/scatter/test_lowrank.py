"""The far field as a hierarchical matrix: its blocks cover every pair once, and its product follows the sum of
every fitted pair to the error its cross approximations were asked for."""

import numba
import numpy as np
import pytest

from tests.scatter import pairs
from translucency.geometry.synthetic import icosphere, torus
from translucency.scatter import crosses, cutoff, fits, kernels, lowrank
from translucency.scatter.hierarchy import SourceTree
from translucency.scatter.materials import material

MARBLE = material("marble").medium()


@numba.njit(cache=True)
def _every_pair(model, P, N, params, dirs, pinv, values):
    """``sum_j (a + b . w)_oj`` over every source ``j``, per receiver and channel (the fits of
    :func:`tests.scatter.pairs.fitted_pairs` one pair at a time)."""
    n, n_c = P.shape[0], params.shape[0]
    out = np.zeros((n, n_c))
    work = np.empty((max(dirs.shape[0], 9), pairs.FIT_WORK_COLUMNS))
    fit = np.empty((n_c, fits.AFFINE_TERMS))
    for o in range(n):
        for j in range(n):
            pairs.fitted_pairs(
                model, P[o, 0] - P[j, 0], P[o, 1] - P[j, 1], P[o, 2] - P[j, 2], N[j, 0], N[j, 1], N[j, 2],
                N[o, 0], N[o, 1], N[o, 2], params, dirs, pinv, work, fit,
            )  # fmt: skip
            for c in range(n_c):
                for t in range(fits.AFFINE_TERMS):
                    out[o, c] += fit[c, t] * values[j, c, t]
    return out


def _surface(kind):
    if kind == "sphere":
        points, triangles = icosphere(4, 20.0)
    else:
        points, triangles = torus(20.0, 8.0, 64, 32)
    normals = points - points.mean(axis=0) if kind == "sphere" else _torus_normals(points)
    return np.ascontiguousarray(points), np.ascontiguousarray(normals / np.linalg.norm(normals, axis=1)[:, None])


def _torus_normals(points):
    ring = points.copy()
    ring[:, 2] = 0.0
    ring *= 20.0 / np.linalg.norm(ring, axis=1)[:, None]
    return points - ring


def _light(points, normals, rng):
    """Flux and ``Psi`` of a directional light (no shadows) with a refracted direction bent off ``-n``."""
    light = np.array([0.3, 0.5, 0.8]) / np.linalg.norm([0.3, 0.5, 0.8])
    flux = np.clip(normals @ light, 0.0, None)
    w = -(0.8 * normals - 0.2 * light)
    w /= np.linalg.norm(w, axis=1)[:, None]
    values = np.zeros((len(points), 3, 4))
    values[:, :, 0] = flux[:, None] * rng.uniform(0.5, 1.0, size=(len(points), 3))
    values[:, :, 1:] = values[:, :, :1] * w[:, None, :]
    return values


def _build(points, normals, eps, model="directional", held=None, medium=MARBLE):
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, model)
    fit = fits.fit_directions(medium.eta, fits.AFFINE_TERMS)
    n = len(points)
    held = held or (np.zeros(n + 1, dtype=np.int64), np.zeros(0, dtype=np.int64))
    gap = 1.0 / float(np.min(medium.sigma_t_reduced))
    matrix = lowrank.build(
        kernels.MODELS[model], points, normals, params, fit, eps, gap,
        lambda r: cutoff.pair_bound(medium, model, r), held,
    )  # fmt: skip
    return matrix, params, fit


def test_the_blocks_cover_every_pair_once_and_far_blocks_are_well_separated():
    points, _ = _surface("sphere")
    tree = SourceTree(points, lowrank.LEAF_SIZE)
    far, dense = lowrank.partition(tree, gap=0.5)
    covered = np.zeros((len(points), len(points)), dtype=np.int64)
    for a, b in np.concatenate([far, dense]):
        covered[tree.start[a] : tree.end[a], tree.start[b] : tree.end[b]] += 1
    assert np.all(covered == 1)
    distance = np.linalg.norm(tree.centre[far[:, 0]] - tree.centre[far[:, 1]], axis=1)
    larger = np.maximum(tree.radius[far[:, 0]], tree.radius[far[:, 1]])
    assert np.all(larger <= lowrank.ETA * distance)
    assert np.all(distance - tree.radius[far[:, 0]] - tree.radius[far[:, 1]] >= 0.5)
    assert len(far) > 100  # the sphere is large against its leaves: most of it is far


@pytest.mark.parametrize("kind", ["sphere", "torus"])
@pytest.mark.parametrize("eps", [1e-2, 1e-3])
def test_the_product_follows_every_pair_to_eps_per_receiver(kind, eps):
    points, normals = _surface(kind)
    values = _light(points, normals, np.random.default_rng(0))
    matrix, params, (dirs, pinv) = _build(points, normals, eps)
    assert matrix.stats["far_blocks"] > 0 and matrix.stats["rank_mean"] > 1
    reference = _every_pair(0, points, normals, params, dirs, pinv, values)
    keep = reference > 1e-4 * reference.max(axis=0)  # the receivers tol holds (docs/physics.md §8.5)
    error = np.abs(matrix.apply(values) - reference)[keep] / reference[keep]
    # each row is held to eps; a receiver's error adds over its far blocks
    assert np.percentile(error, 99) < 2 * eps
    assert error.max() < 10 * eps
    if eps >= 1e-2:  # compressed: fewer numbers than the pairs it stands for (four per channel each)
        assert matrix.stats["far_floats"] + matrix.stats["dense_floats"] < 0.5 * len(points) ** 2 * 12


def test_a_radial_model_has_no_direction_terms_and_is_followed_too():
    points, normals = _surface("sphere")
    values = _light(points, normals, np.random.default_rng(1))
    matrix, params, (dirs, pinv) = _build(points, normals, 1e-3, model="standard")
    reference = _every_pair(1, points, normals, params, dirs, pinv, values)
    keep = reference > 1e-4 * reference.max(axis=0)
    error = np.abs(matrix.apply(values) - reference)[keep] / reference[keep]
    assert np.percentile(error, 99) < 2e-3


def test_held_pairs_are_zero_in_dense_blocks_and_given_where_a_low_rank_block_holds_them():
    points, normals = _surface("sphere")
    n = len(points)
    rng = np.random.default_rng(2)
    receivers = rng.choice(n, 12, replace=False)
    # each receiver holds its nearest vertex (a dense block) and one a quarter round the sphere (a low-rank one;
    # not across it: there the receiver is on the source's normal line, where the modified tangent plane turns
    # abruptly (docs/physics.md §4.1), and the blocks need more crosses than they may take, so they are dense)
    distance = np.linalg.norm(points[receivers, None] - points[None], axis=2)
    distance[np.arange(12), receivers] = np.inf
    nearest = np.argmin(distance, axis=1)
    farthest = np.argmin(np.abs(distance - 20.0 * np.sqrt(2.0)), axis=1)
    starts = np.zeros(n + 1, dtype=np.int64)
    counts = np.zeros(n, dtype=np.int64)
    counts[receivers] = 2
    np.cumsum(counts, out=starts[1:])
    columns = np.empty(starts[-1], dtype=np.int64)
    columns[starts[receivers]] = nearest
    columns[starts[receivers] + 1] = farthest
    matrix, _, _ = _build(points, normals, 1e-3, held=(starts, columns))
    taken = np.zeros((starts[-1], 3 * 4), dtype=np.float32)  # the near field's coefficients, as relighting holds them
    matrix.take_low_rank_entries(starts, columns, taken, 4)
    held = -taken.reshape(-1, 3, 4)
    for r, o in enumerate(receivers):
        for j, k in ((nearest[r], starts[o]), (farthest[r], starts[o] + 1)):
            values = np.zeros((n, 3, 4))
            values[j] = rng.normal(size=(3, 4))
            B = matrix.apply(values)[o]  # the matrix's entry (o, j): 0 where a dense block leaves it out
            np.testing.assert_allclose(B, np.sum(held[k] * values[j], axis=1), rtol=1e-5, atol=1e-30)
        assert np.all(held[starts[o]] == 0.0)  # the nearest is in a dense block, left out there
    assert np.mean([np.any(held[starts[o] + 1] != 0.0) for o in receivers]) >= 0.75


#: The ``eps`` at which the budget's count of the crosses is tested.
COUNTED_EPS = 1e-3


def _torus_count(medium):
    """The torus's block tree, its far and dense pairs, and ``count(blocks)``: :func:`crosses.sampled_count` of its
    far blocks in ``medium`` at :data:`COUNTED_EPS` on ``blocks`` of them."""
    points, normals = _surface("torus")
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, "directional")
    fit = fits.fit_directions(medium.eta, fits.AFFINE_TERMS)
    tree = SourceTree(points, lowrank.LEAF_SIZE)
    far_pairs, dense_pairs = lowrank.partition(tree, 1.0 / float(np.min(medium.sigma_t_reduced)))

    def count(blocks):
        return crosses.sampled_count(
            kernels.MODELS["directional"], tree, points, normals, params, fit, COUNTED_EPS, far_pairs,
            lambda r: cutoff.pair_bound(medium, "directional", r), blocks=blocks,
        )  # fmt: skip

    return tree, far_pairs, dense_pairs, count


@pytest.mark.parametrize("name", ["marble", "skim_milk", "ketchup"])
def test_the_count_before_the_build_is_what_the_build_holds(name):
    """The budget's count of the crosses (relight.operator_bytes): every block counted, it is what the build stores;
    a sample of the blocks counted, it is within a tenth of it, in each material."""
    medium = material(name).medium()
    points, normals = _surface("torus")
    matrix, _, _ = _build(points, normals, COUNTED_EPS, medium=medium)
    tree, far_pairs, dense_pairs, count = _torus_count(medium)
    assert len(far_pairs) * 3 > 2 * crosses.SAMPLED_BLOCKS  # the count draws a sample
    sampled = count(crosses.SAMPLED_BLOCKS)
    every = count(10**9)
    stored = matrix.U.nbytes + matrix.V.nbytes + matrix.V8.nbytes
    assert every["cross_bytes"] == stored and every["row_scales"] == matrix.U_scale.size
    sizes = tree.end - tree.start
    whole = 3 * np.sum(sizes[dense_pairs[:, 0]] * sizes[dense_pairs[:, 1]])
    assert 4 * (whole + every["dense_entries"]) == matrix.D.size
    assert abs(sampled["cross_bytes"] / stored - 1.0) < 0.1
    assert abs(sampled["row_scales"] / matrix.U_scale.size - 1.0) < 0.1


def test_the_sampled_count_is_what_every_block_counts_on_average_over_its_starts(monkeypatch):
    """Hansen and Hurwitz's estimate is unbiased: over many starts of the systematic draw, every count (blocks drawn
    twice counted twice) averages what counting every block gives."""
    tree, far_pairs, _, count = _torus_count(MARBLE)
    every = count(10**9)
    size = tree.end - tree.start
    weights = (size[far_pairs[:, 0]] + 4 * size[far_pairs[:, 1]]).repeat(3)
    assert weights.max() > weights.sum() / crosses.SAMPLED_BLOCKS  # some blocks are drawn more than once
    starts = []
    for seed in range(24):
        monkeypatch.setattr(crosses, "SAMPLE_SEED", seed)
        starts.append(count(crosses.SAMPLED_BLOCKS))
    for key in ("cross_bytes", "row_scales", "fits"):
        assert abs(np.mean([start[key] for start in starts]) / every[key] - 1.0) < 0.02, key


def _in_fixed_point(U, V, narrow):
    """One block's components ``U (m, k)``, ``V (k, columns)`` in the store's fixed point (``crosses.fixed_point``):
    ``U``, ``V``, ``U``'s row scales and the last ``narrow`` rows of ``V``, each flat."""
    (m, k), columns = U.shape, V.shape[1]
    parts = (np.empty(k * m, np.int16), np.empty((k - narrow) * columns, np.int16))
    parts += (np.empty(m, np.float32), np.empty(narrow * columns, np.int8))
    crosses.fixed_point(
        U, V, parts[0].reshape(k, m), parts[2], parts[1].reshape(k - narrow, columns), parts[3].reshape(narrow, columns)
    )
    return parts


def test_the_crosses_store_grows_past_what_it_reserved_and_keeps_every_block():
    store = lowrank._CrossStore(5, 7, 2)  # room for less than one block
    rng = np.random.default_rng(0)
    blocks = [
        (rng.normal(size=(m, k)) * np.logspace(0, -30, m)[:, None], rng.uniform(-1.0, 1.0, size=(k, 4 * n)), narrow)
        for m, k, n, narrow in [(3, 2, 4, 1), (8, 5, 2, 0), (1, 1, 1, 1)]
    ]
    blocks[1][0][4] = 0.0  # a row of zeros stays zero
    places = [store.put_converted(*_in_fixed_point(U, V, narrow)) for U, V, narrow in blocks]
    U_all, V_all, scales, V8_all = store.arrays()
    assert U_all.size == sum(U.size for U, _, _ in blocks)
    assert V_all.size == sum((V.shape[0] - narrow) * V.shape[1] for _, V, narrow in blocks)
    assert V8_all.size == sum(narrow * V.shape[1] for _, V, narrow in blocks)
    assert scales.size == sum(U.shape[0] for U, _, _ in blocks)
    for (U, V, narrow), (u_at, v_at, s_at, v8_at) in zip(blocks, places):
        held = U_all[u_at : u_at + U.size].reshape(U.shape[1], U.shape[0]).T * scales[s_at : s_at + U.shape[0], None]
        # each row to half a step of its own largest entry, however small the row
        largest = np.abs(U).max(axis=1, keepdims=True)
        assert np.all(np.abs(held - U) <= 0.5001 * largest / crosses.FIXED_STEPS)
        wide = V.shape[0] - narrow
        np.testing.assert_allclose(
            V_all[v_at : v_at + wide * V.shape[1]].reshape(wide, V.shape[1]) * crosses.V_STEP,
            V[:wide],
            atol=crosses.V_STEP,
        )
        np.testing.assert_allclose(  # the last rows in 8 bits, each entry to half a step
            V8_all[v8_at : v8_at + narrow * V.shape[1]].reshape(narrow, V.shape[1]) * crosses.V8_STEP,
            V[wide:],
            atol=0.5001 * crosses.V8_STEP,
        )


def _stored_product(matrix, tree_values):
    """``B (n, C)`` in the tree's order for ``tree_values (C, 4 n)``, block by block in numpy from the stored
    components (``U`` one at a time, in steps of its row scales; ``V`` in steps of ``V_STEP``, its last ``k8`` rows of
    ``V8_STEP``) and dense blocks."""
    n = matrix.order.size
    B = np.zeros((n, matrix.n_channels))
    terms = fits.AFFINE_TERMS
    for r0, r1, c0, c1, c, k, u_at, v_at, s_at, k8, v8_at in matrix.low_rank:
        m, columns = r1 - r0, (c1 - c0) * terms
        U = matrix.U[u_at : u_at + m * k].reshape(k, m).T * matrix.U_scale[s_at : s_at + m, None].astype(np.float64)
        V = np.concatenate(
            [
                matrix.V[v_at : v_at + (k - k8) * columns].reshape(k - k8, columns) * crosses.V_STEP,
                matrix.V8[v8_at : v8_at + k8 * columns].reshape(k8, columns) * crosses.V8_STEP,
            ]
        )
        B[r0:r1, c] += U @ (V @ tree_values[c, c0 * terms : c1 * terms])
    for r0, r1, c0, c1, first, last, at in matrix.dense:
        m, columns = r1 - r0, (c1 - c0) * terms
        block = matrix.D[at : at + (last - first) * m * columns].reshape(last - first, m, columns)
        for c in range(first, last):
            B[r0:r1, c] += block[c - first] @ tree_values[c, c0 * terms : c1 * terms]
    return B


def test_a_light_on_part_of_the_surface_gives_the_stored_matrix_product():
    """Blocks whose sources are all in shadow are skipped: the product is the stored matrix's, multiplied apart
    block by block, for lit patches of every length with gaps between them, no light and light everywhere."""
    points, normals = _surface("sphere")
    matrix, _, _ = _build(points, normals, 1e-2)
    assert matrix.stats["far_blocks"] > 100
    rng = np.random.default_rng(3)
    n = len(points)
    for share in (0.0, 0.05, 0.5, 1.0):
        lit = np.zeros(n, dtype=bool)
        at = 0
        while at < n:  # in the tree's order: patches of 1-30 lit sources, gaps of 1-24
            length = rng.integers(1, 30)
            lit[at : at + length] = rng.uniform() < share or share == 1.0
            at += length + (0 if share == 1.0 else rng.integers(1, 25))
        values = rng.normal(size=(n, matrix.n_channels, fits.AFFINE_TERMS))
        values[matrix.order[~lit]] = 0.0
        tree_values = values[matrix.order].transpose(1, 0, 2).reshape(matrix.n_channels, -1)
        expected = np.empty((n, matrix.n_channels))
        expected[matrix.order] = _stored_product(matrix, tree_values)
        scale = np.abs(expected).max()
        np.testing.assert_allclose(matrix.apply(values), expected, rtol=0, atol=1e-5 * max(scale, 1e-300))
        if share == 0.0:
            assert np.all(matrix.apply(values) == 0.0)


@pytest.mark.parametrize("m, n, k", [(40, 160, 12), (7, 300, 7), (200, 64, 30), (30, 120, 1), (150, 400, 80)])
def test_the_recompressed_crosses_keep_the_block_and_only_the_singular_values_it_needs(m, n, k):
    """A block given as ``k`` crosses whose singular values fall over six decades: recompressed, the product moves by
    at most RECOMPRESS_SHARE eps of its norm, it keeps as many components as numpy's SVD says that allows, each V row
    is in [-1, 1] with its largest entry 1, and the rows held in 8 bits add at most NARROW_SHARE eps when rounded."""
    rng = np.random.default_rng(k)
    eps = 1e-2
    left, _ = np.linalg.qr(rng.normal(size=(m, k)))
    right, _ = np.linalg.qr(rng.normal(size=(n, k)))
    singular = np.logspace(0, -6, k)
    mix = rng.normal(size=(k, k))  # crosses that are not orthogonal
    U0 = (left * singular) @ mix
    V0 = np.linalg.solve(mix, right.T)
    block = U0 @ V0
    U = np.zeros((m + 3, k + 2))
    V = np.zeros((k + 2, n + 5))
    U[:m, :k], V[:k, :n] = U0, V0
    kept, narrow = crosses._recompressed(U, V, m, n, k, eps, V0 @ V0.T)
    s = np.linalg.svd(block, compute_uv=False)
    tail = np.sqrt(np.cumsum(s[::-1] ** 2)[::-1])  # tail[q]: what leaving out components q.. drops
    expected = int(np.sum(tail > crosses.RECOMPRESS_SHARE * eps * np.linalg.norm(block)))
    assert kept == expected
    product = U[:m, :kept] @ V[:kept, :n]
    assert np.linalg.norm(product - block) <= crosses.RECOMPRESS_SHARE * eps * np.linalg.norm(block) * 1.0001
    np.testing.assert_allclose(np.abs(V[:kept, :n]).max(axis=1), 1.0)
    assert 0 <= narrow <= kept
    rounded = V[:kept, :n].copy()
    rounded[kept - narrow :] = np.rint(rounded[kept - narrow :] * crosses.NARROW_STEPS) / crosses.NARROW_STEPS
    moved = np.linalg.norm(U[:m, :kept] @ rounded - product)
    assert moved <= crosses.NARROW_SHARE * eps * np.linalg.norm(block) * 1.0001
    if k > 4:
        assert narrow > 0  # the smallest components are well below what 8 bits lose


@pytest.mark.parametrize("k", [1, 9, crosses.LAPACK_LARGEST, crosses.LAPACK_LARGEST + 1, 90])
def test_the_recompression_s_eigenvectors_are_numpy_s_whichever_way_they_are_found(k):
    """Up to LAPACK_LARGEST by LAPACK, above by Jacobi rotations: the eigenvalues of a symmetric matrix whose
    eigenvalues fall over twelve decades, descending, within 1e-12 of the largest of numpy's, and the eigenvectors
    reproduce it."""
    rng = np.random.default_rng(k)
    basis, _ = np.linalg.qr(rng.normal(size=(k, k)))
    values = np.logspace(0, -12, k)
    A = (basis * values) @ basis.T
    A = 0.5 * (A + A.T)
    found, vectors = crosses._symmetric_eigen(A.copy())
    np.testing.assert_allclose(found, np.sort(np.linalg.eigvalsh(A))[::-1], rtol=0, atol=1e-12)
    np.testing.assert_allclose((vectors * found) @ vectors.T, A, rtol=0, atol=1e-12)
    np.testing.assert_allclose(vectors.T @ vectors, np.eye(k), rtol=0, atol=1e-10)


def test_crosses_that_are_not_finite_are_left_as_they_are():
    """A NaN in a block's crosses is not recompressed away: the crosses stay, all 16-bit, and B will show it."""
    rng = np.random.default_rng(5)
    U, V = rng.normal(size=(20, 6)), rng.uniform(-1.0, 1.0, size=(6, 40))
    U[3, 2] = np.nan
    before_U, before_V = U.copy(), V.copy()
    assert crosses._recompressed(U, V, 20, 40, 4, 1e-2, V @ V.T) == (4, 0)
    np.testing.assert_array_equal(U, before_U)
    np.testing.assert_array_equal(V, before_V)
