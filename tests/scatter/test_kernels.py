"""numba kernels against the float64 reference formulas of translucency.scatter.dipoles (relative 1e-12)."""

import numpy as np
import pytest

from tests.scatter import pairs
from translucency.scatter import dipoles, fresnel, kernels, listsums
from translucency.scatter.hierarchy import opening
from translucency.scatter.materials import material


def _pairs(rng, n, spread):
    x_i = rng.normal(size=(n, 3)) * spread
    x_o = x_i + rng.normal(size=(n, 3)) * spread * rng.random((n, 1))
    n_i = rng.normal(size=(n, 3))
    n_i /= np.linalg.norm(n_i, axis=1, keepdims=True)
    n_o = rng.normal(size=(n, 3))
    n_o /= np.linalg.norm(n_o, axis=1, keepdims=True)
    light = rng.normal(size=(n, 3))
    light /= np.linalg.norm(light, axis=1, keepdims=True)
    light = np.where((np.sum(light * n_i, 1) < 0)[:, None], light - 2 * np.sum(light * n_i, 1)[:, None] * n_i, light)
    return x_i, n_i, light, x_o, n_o


def test_pair_matches_every_reference_vector(dirpole_vectors):
    for case in dirpole_vectors["edge_cases"] + dirpole_vectors["random"]:
        w12 = fresnel.refract(case["w_i"], case["n_i"], case["eta"])
        params = kernels.channel_parameters(case["sigma_a"], case["sigma_s"], case["g"], case["eta"])
        out = np.empty(1)
        pairs.directional_dipole_pair(*case["x_i"], *case["n_i"], *w12, *case["x_o"], *case["n_o"], params, out)
        if case["S_d"] == 0:
            assert out[0] == pytest.approx(0.0, abs=1e-15)
        else:
            assert out[0] == pytest.approx(case["S_d"], rel=1e-12)


@pytest.mark.parametrize("name", ["marble", "ketchup", "skim_milk", "white_grapefruit_juice"])
@pytest.mark.parametrize("model", ["directional", "standard", "better"])
def test_all_channels_at_once_match_reference(name, model):
    medium = material(name).medium()
    rng = np.random.default_rng(11)
    x_i, n_i, light, x_o, n_o = _pairs(rng, 3000, 2.0 / np.mean(medium.sigma_t_reduced))
    x_o[:5] = x_i[:5]  # r = 0 included
    w12 = fresnel.refract(light, n_i, medium.eta)
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, model)
    got = pairs.model_pairs(kernels.MODELS[model], x_i, n_i, w12, x_o, n_o, params)
    r = np.linalg.norm(x_o - x_i, axis=1)
    for c in range(3):
        args = (medium.sigma_a[c], medium.sigma_s[c], medium.g[c], medium.eta)
        if model == "directional":
            ref = dipoles.directional_dipole(x_i, n_i, w12, x_o, n_o, *args)
        elif model == "standard":
            ref = dipoles.standard_dipole_profile(r, *args) / np.pi
        else:
            ref = dipoles.better_dipole_profile(r, *args) / (np.pi * 4 * fresnel.C_phi(1 / medium.eta))
        scale = np.max(ref)
        assert np.allclose(got[:, c], ref, rtol=1e-12, atol=1e-15 * scale)


def test_vertex_sum_equals_dense_reference_sum():
    rng = np.random.default_rng(5)
    medium = material("potato").medium()
    x_i, n_i, light, _, _ = _pairs(rng, 300, 3.0)
    x_o, n_o = x_i[:120], n_i[:120]
    w12 = fresnel.refract(light, n_i, medium.eta)
    flux = rng.random((300, 3))
    flux[::7] = 0.0
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta)
    B, clamped = kernels.vertex_sum(0, x_i, n_i, w12, flux, x_o, n_o, params, np.arange(3))
    for c in range(3):
        S = dipoles.directional_dipole(
            x_i[None],
            n_i[None],
            w12[None],
            x_o[:, None],
            n_o[:, None],
            medium.sigma_a[c],
            medium.sigma_s[c],
            medium.g[c],
            medium.eta,
        )
        assert np.allclose(B[:, c], S @ flux[:, c], rtol=1e-12, atol=0)
    assert clamped.shape == (120,) and clamped.min() >= 0


def test_channel_map_reuses_identical_channels():
    medium = material("marble").medium()
    params = kernels.channel_parameters(medium.sigma_a[:1], medium.sigma_s[:1], medium.g[:1], medium.eta)
    rng = np.random.default_rng(2)
    x_i, n_i, light, _, _ = _pairs(rng, 50, 2.0)
    w12 = fresnel.refract(light, n_i, medium.eta)
    flux = rng.random((50, 3))
    B, _ = kernels.vertex_sum(0, x_i, n_i, w12, flux, x_i, n_i, params, np.zeros(3, dtype=np.int64))
    B1, _ = kernels.vertex_sum(0, x_i, n_i, w12, flux[:, :1], x_i, n_i, params, np.zeros(1, dtype=np.int64))
    assert np.allclose(B[:, 0], B1[:, 0], rtol=1e-14)


@pytest.mark.parametrize("model", ["directional", "standard", "better"])
def test_one_kernel_for_every_model_and_channel_map(model):
    """vertex_sum is the dense reference sum for every model, for 1-3 distinct parameter rows mapped to the
    output channels, and for more than three output channels (lanes in groups of three); a row's clamps
    are counted once however many channels share it."""
    rng = np.random.default_rng(9)
    medium = material("skin1").medium()
    x_i, n_i, light, _, _ = _pairs(rng, 400, 2.0)
    x_i[:3] = x_i[3]  # coincident sources and receivers (r = 0)
    w12 = fresnel.refract(light, n_i, medium.eta)
    profiles = {
        "directional": None,
        "standard": dipoles.standard_dipole_profile,
        "better": dipoles.better_dipole_profile,
    }
    reference = []
    for c in range(3):
        coefficients = (medium.sigma_a[c], medium.sigma_s[c], medium.g[c], medium.eta)
        if model == "directional":
            S = dipoles.directional_dipole(
                x_i[None], n_i[None], w12[None], x_i[:150, None], n_i[:150, None], *coefficients
            )
        else:
            r = np.linalg.norm(x_i[:150, None] - x_i[None], axis=2)
            scale = 1.0 / np.pi if model == "standard" else 1.0 / (np.pi * 4.0 * fresnel.C_phi(1.0 / medium.eta))
            S = scale * profiles[model](r, *coefficients)
        reference.append(S)
    code = kernels.MODELS[model]
    single = []
    for rows, channel_of in ((3, [0, 1, 2]), (1, [0, 0, 0]), (2, [0, 1, 1]), (3, [0, 1, 2, 2, 0])):
        channel_of = np.array(channel_of, dtype=np.int64)
        flux = rng.random((400, channel_of.size))
        params = kernels.channel_parameters(
            medium.sigma_a[:rows], medium.sigma_s[:rows], medium.g[:rows], medium.eta, model
        )
        B, clamped = kernels.vertex_sum(code, x_i, n_i, w12, flux, x_i[:150], n_i[:150], params, channel_of)
        for c, row in enumerate(channel_of):
            assert np.allclose(B[:, c], reference[row] @ flux[:, c], rtol=1e-12, atol=0)
        if rows == 3 and channel_of.size == 3:
            for c in range(3):
                one = kernels.channel_parameters(
                    medium.sigma_a[c : c + 1], medium.sigma_s[c : c + 1], medium.g[c : c + 1], medium.eta, model
                )
                single.append(
                    kernels.vertex_sum(
                        code, x_i, n_i, w12, flux[:, :1], x_i[:150], n_i[:150], one, np.zeros(1, dtype=np.int64)
                    )[1]
                )
            assert np.array_equal(clamped, sum(single))
        else:
            assert np.array_equal(clamped, sum(single[:rows]))
    if model == "directional":
        assert sum(single).sum() > 0  # backlit pairs are clamped and counted
    else:
        assert sum(single).sum() == 0  # the radial profiles are positive


def test_exp_nonpositive_is_accurate():
    x = -np.concatenate([np.linspace(0, 50, 20001), np.geomspace(1e-12, 745, 2001)])
    approx = np.array([kernels.exp_nonpositive(v) for v in x[::7]])
    exact = np.exp(x[::7])
    assert np.all(np.abs(approx - exact) <= 5e-13 * exact)
    assert kernels.exp_nonpositive(-800.0) == 0.0


def test_exp_nonpositive_in_float32_is_float32_and_within_2e_5():
    """Handed a float32, the exponential computes in float32 (7 squarings, not 12): within 2e-5 of ``e^x`` on
    ``[-87, 0]``, and further from the float64 result than float64's own rounding, which it would match if a
    constant had widened it."""
    x = -np.concatenate([np.linspace(0, 87, 4001), np.geomspace(1e-7, 87, 401)]).astype(np.float32)
    approx = np.array([kernels.exp_nonpositive(v) for v in x])
    exact = np.exp(x.astype(np.float64))
    error = np.abs(approx - exact) / exact
    assert error.max() <= 2e-5
    assert error.max() > 1e-9
    assert kernels.exp_nonpositive(np.float32(-110.0)) == 0.0  # underflows, as float64's does past -746


@pytest.mark.parametrize("model", ["directional", "standard", "better"])
@pytest.mark.parametrize("channel_of", [[0, 1, 2], [0], [0, 1, 2, 2, 0]])
@pytest.mark.parametrize(("precision", "rel"), [(np.float64, 1e-11), (np.float32, 5e-5)])
def test_grouped_sum_is_the_dense_sum_over_each_groups_list(model, channel_of, precision, rel):
    """grouped_sum against the reference dipoles summed here over each group's random list (with
    repeats), for groups of 4 and a last group that is short, every model and 1, 3 or 5 channels, in float64
    (to 1e-11) and in float32 (to 5e-5: each pair within about 2e-5, and the directional dipole's real and virtual
    sources cancel in part; and further from float64 than its rounding, or it was not float32). The rows from 100 on
    are clusters, each pair of theirs times the second order of its random spread written out here (docs/physics.md
    §8.3), its bends read at the group's first receiver's distance."""
    rng = np.random.default_rng(11)
    medium = material("skin1").medium()
    x_i, n_i, light, _, _ = _pairs(rng, 300, 2.0)
    w12 = fresnel.refract(light, n_i, medium.eta)
    channel_of = np.array(channel_of, dtype=np.int64)
    flux = rng.random((300, channel_of.size))
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, model)
    x_i = x_i + 500.0  # far from the origin: the sums take positions from each group's first receiver
    records = np.hstack([x_i, n_i, w12, flux])
    n_rcv, group = 37, 4
    n_groups = -(-n_rcv // group)
    counts = rng.integers(0, 120, size=n_groups)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    columns = rng.integers(0, 300, size=int(counts.sum()))
    receivers = rng.choice(300, n_rcv, replace=False)
    lanes = kernels.channel_lanes(params, channel_of, channel_of.size)
    shape = rng.normal(size=(200, 3, 3)) * 0.15  # mm: RMS spreads of a few tenths of a mm
    covariance = shape @ shape.transpose(0, 2, 1)
    spread = covariance[:, [0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]
    rule = opening(medium, model, 0.01)
    bends = rule.bends[channel_of]
    arguments = (
        kernels.MODELS[model],
        x_i[receivers],
        n_i[receivers],
        records,
        spread,
        (bends, rule.log_first, rule.per_log),
        100,
        starts,
        counts,
        group,
        columns,
        lanes,
    )
    B = listsums.grouped_sum(*arguments, precision)
    if precision is np.float32:
        B64 = listsums.grouped_sum(*arguments, np.float64)
        assert np.max(np.abs(B - B64) / np.maximum(B64, 1e-300)) > 1e-9
    for r in range(n_rcv):
        g = r // group
        listed = columns[starts[g] : starts[g] + counts[g]]
        for c, row in enumerate(channel_of):
            coefficients = (medium.sigma_a[row], medium.sigma_s[row], medium.g[row], medium.eta)
            if model == "directional":
                S = dipoles.directional_dipole(
                    x_i[listed], n_i[listed], w12[listed], x_i[receivers[r]], n_i[receivers[r]], *coefficients
                )
                S = np.maximum(S, 0.0)
            else:
                profile = dipoles.standard_dipole_profile if model == "standard" else dipoles.better_dipole_profile
                scale = 1.0 / np.pi if model == "standard" else 1.0 / (np.pi * 4.0 * fresnel.C_phi(1.0 / medium.eta))
                S = scale * profile(np.linalg.norm(x_i[listed] - x_i[receivers[r]], axis=1), *coefficients)
            x = x_i[receivers[r]] - x_i[listed]
            r2 = np.sum(x * x, axis=1)
            head = x_i[receivers[g * group]] - x_i[listed]
            head = np.maximum(np.linalg.norm(head, axis=1), 1e-300)  # at 0: the table's first distance
            at = np.clip(((np.log(head) - rule.log_first) * rule.per_log).astype(int), 0, None)
            line = bends[c][:, at]
            along = line[0] + line[1] * np.sqrt(r2)
            across = line[2] + line[3] * np.sqrt(r2)
            with np.errstate(divide="ignore", invalid="ignore"):
                c_along = np.einsum("ki,kij,kj->k", x, covariance[np.maximum(listed - 100, 0)], x) / r2
                trace = np.trace(covariance[np.maximum(listed - 100, 0)], axis1=1, axis2=2)
                factor = np.clip(1.0 + 0.5 / r2 * (along * c_along + across * (trace - c_along)), 0.5, 2.0)
            factor[r2 == 0] = 1.0  # a cluster at the receiver (not in a walk's lists): its pair alone
            S = np.where(listed >= 100, S * factor, S)
            assert B[r, c] == pytest.approx(float(S @ flux[listed, c]), rel=rel, abs=1e-300)
