"""granagg.analysis against independent references: SciPy's cKDTree and connected components
for contact clusters, scipy.ndimage.label with periodic merging for grid clusters, a direct NumPy
sum over particles for S(k), exact power laws and Maxwellian samples (fixed seeds; tolerances
from the expected spread, stated at each test)."""
import math

import numpy as np
import pytest
from scipy import ndimage, sparse
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from granagg.analysis import (GridClusters, GrowthExponent, Msd, ParticleClusters, PowerLawMle,
                              SpeedDistribution, StructureFactor)


def blobs(L, n_blobs, per_blob, radius, seed):
    """Clustered positions: Gaussian blobs of particles at random centres, wrapped."""
    rng = np.random.default_rng(seed)
    centres = rng.uniform(0, L, (n_blobs, 3))
    pts = centres.repeat(per_blob, axis=0) + rng.normal(0, radius, (n_blobs * per_blob, 3))
    return np.mod(pts, L)


def same_partition(a, b):
    """True when two labelings group the items alike (labels may be numbered differently)."""
    a, b = np.asarray(a).ravel(), np.asarray(b).ravel()
    if a.shape != b.shape:
        return False
    pairs = set(zip(a.tolist(), b.tolist()))
    return len(pairs) == len(set(a.tolist())) == len(set(b.tolist()))


def mean_size(sizes):
    sizes = np.asarray(sizes, dtype=float)
    return float((sizes ** 2).sum() / sizes.sum())


# ---- particle clusters ---------------------------------------------------------------------

@pytest.mark.parametrize("seed", [1, 2])
def test_particle_clusters_equal_ckdtree_components(seed):
    L, tol = 15.0, 0.05
    pos = blobs(L, 12, 40, 0.9, seed)
    pc = ParticleClusters(tolerance=tol).compute(L, pos)
    pairs = cKDTree(pos, boxsize=L).query_pairs(1.0 + tol, output_type="ndarray")
    graph = sparse.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])),
                              shape=(len(pos), len(pos)))
    n, ref = connected_components(graph, directed=False)
    assert len(pc.cluster_sizes) == n
    assert same_partition(pc.labels, ref)
    assert pc.bonds == len(pairs)
    assert pc.S == pytest.approx(mean_size(np.bincount(ref)), rel=1e-12)
    s, N_s = pc.size_distribution
    assert int((s * N_s).sum()) == len(pos)
    assert pc.largest_share == pytest.approx(np.bincount(ref).max() / len(pos), rel=1e-12)


def test_clusters_across_the_periodic_boundary_are_one():
    # a chain of touching particles that crosses x = 0: one cluster, as cKDTree with boxsize says
    L = 10.0
    x = np.array([9.0, 9.9, 0.8, 1.7])
    pos = np.stack([x, np.full(4, 5.0), np.full(4, 5.0)], axis=1)
    pc = ParticleClusters().compute(L, pos)
    assert list(pc.cluster_sizes) == [4]
    # positions given outside [0, L) are their periodic images: the same clusters
    shifted = pos + np.array([L, -2 * L, 3 * L])
    assert same_partition(ParticleClusters().compute(L, shifted).labels, pc.labels)


# ---- grid clusters -------------------------------------------------------------------------

def periodic_label(occupied):
    """scipy.ndimage.label (6-connectivity) with the labels merged across the periodic faces."""
    labels, n = ndimage.label(occupied)
    parent = list(range(n + 1))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for axis in range(3):
        first = np.take(labels, 0, axis=axis)
        last = np.take(labels, -1, axis=axis)
        for a, b in zip(first.ravel(), last.ravel()):
            if a and b:
                parent[find(a)] = find(b)
    roots = np.array([find(i) for i in range(n + 1)])
    merged = np.where(labels > 0, roots[labels], 0)
    return merged


@pytest.mark.parametrize("seed", [3, 4])
def test_grid_labels_equal_ndimage_with_periodic_merging(seed):
    L = 24.0
    pos = blobs(L, 10, 120, 1.2, seed)
    gc = GridClusters(spacing=2.0, min_fill=0.25).compute(L, pos)
    n = gc.cells_per_side
    h = L / n
    assert h == pytest.approx(gc.cell_size)
    cells = np.minimum((pos / h).astype(int), n - 1)
    counts = np.zeros((n, n, n))
    np.add.at(counts, (cells[:, 0], cells[:, 1], cells[:, 2]), 1)
    occupied = counts >= gc.min_count
    assert gc.occupied_fraction == pytest.approx(occupied.mean(), rel=1e-12)
    ref = periodic_label(occupied)
    assert ((gc.labels >= 0) == occupied).all()
    assert same_partition(np.where(occupied, gc.labels, -1), np.where(occupied, ref, 0))
    sizes = np.bincount(ref[occupied])[1:]
    sizes = sizes[sizes > 0]
    assert sorted(gc.cluster_sizes) == sorted(sizes)
    assert gc.S == pytest.approx(mean_size(sizes), rel=1e-12)


# ---- S(k) ----------------------------------------------------------------------------------

def direct_shell(pos, L, m):
    """Mean of |sum_j exp(-i k.r_j)|^2 / N over one of each +-k with round(|n|) = m."""
    n = np.arange(-m - 1, m + 2)
    nx, ny, nz = np.meshgrid(n, n, np.arange(0, m + 2), indexing="ij")
    nv = np.stack([nx.ravel(), ny.ravel(), nz.ravel()], axis=1)
    x, y, z = nv.T
    half = (z > 0) | ((z == 0) & ((x > 0) | ((x == 0) & (y > 0))))
    nv = nv[half & (np.rint(np.linalg.norm(nv, axis=1)) == m)]
    rho = np.exp(-1j * (2 * np.pi / L) * pos @ nv.T).sum(axis=0)
    return float((np.abs(rho) ** 2).mean() / len(pos))


@pytest.mark.parametrize("kind", ["clustered", "uniform"])
def test_structure_factor_equals_direct_sum(kind):
    # Tolerance: Jing's window correction is exact in expectation; in one configuration each
    # particle's CIC weight differs from the mean window by O((k h)^2) with a random sign, so
    # |rho_k|^2 / N is off by a relative O((k h)^2) per wave vector, averaged down by the
    # sqrt(counts) independent wave vectors of the shell: rel = (k_m h)^2 / sqrt(counts)
    # (0.8 % at m = 1, where the observed error is 0.35 %, for L = 20, h = 0.5).
    L = 20.0
    rng = np.random.default_rng(5)
    pos = blobs(L, 40, 20, 0.7, 6) if kind == "clustered" else rng.uniform(0, L, (3000, 3))
    sf = StructureFactor().compute(L, pos)
    assert sf.mesh == 40
    h = L / sf.mesh
    for m in (1, 2, 3):
        assert sf.k[m - 1] == pytest.approx(m * 2 * np.pi / L)
        rel = (sf.k[m - 1] * h) ** 2 / np.sqrt(sf.counts[m - 1])
        assert sf.S_k[m - 1] == pytest.approx(direct_shell(pos, L, m), rel=rel)
    # l = 2 pi / k_1, the first moment over k_m <= k_cut
    inside = sf.k <= math.pi
    k1 = (sf.k[inside] * sf.S_k[inside]).sum() / sf.S_k[inside].sum()
    assert sf.length == pytest.approx(2 * np.pi / k1, rel=1e-12)


def test_velocity_structure_of_uncorrelated_velocities_is_one():
    # S_par and S_perp of velocities independent of the positions have expectation 1 per shell;
    # the mean over shells 2..8 (hundreds of modes) lies within 5 % (spread ~ 1/sqrt(modes))
    L = 20.0
    rng = np.random.default_rng(7)
    pos = rng.uniform(0, L, (4000, 3))
    vel = rng.normal(0, 1, (4000, 3))
    sf = StructureFactor().compute(L, pos, vel)
    assert abs(sf.S_par[1:8].mean() - 1) < 0.05
    assert abs(sf.S_perp[1:8].mean() - 1) < 0.05
    assert sf.T_g == pytest.approx((vel - vel.mean(0)).var(axis=0).mean(), rel=1e-3)
    with pytest.raises(AttributeError, match="velocities"):
        StructureFactor().compute(L, pos).l_perp


# ---- ownership, inputs, errors -------------------------------------------------------------

def test_results_are_read_only_and_survive_recompute_and_deletion():
    L = 15.0
    pc = ParticleClusters().compute(L, blobs(L, 5, 30, 0.8, 8))
    labels, sizes = pc.labels, pc.cluster_sizes
    saved = labels.copy()
    assert not labels.flags.writeable
    with pytest.raises(ValueError):
        labels[0] = 7
    pc.compute(L, blobs(L, 6, 30, 0.8, 9))
    assert (labels == saved).all()
    del pc
    assert (labels == saved).all() and sizes.sum() == 150


def test_inputs_float32_read_only_and_no_copy_paths_agree():
    L = 15.0
    pos = blobs(L, 5, 30, 0.8, 10)
    ref = ParticleClusters().compute(L, pos).labels
    ro = pos.copy()
    ro.setflags(write=False)
    assert (ParticleClusters().compute(L, ro).labels == ref).all()
    f32 = pos.astype(np.float32)
    assert same_partition(ParticleClusters().compute(L, f32).labels,
                          ParticleClusters().compute(L, f32.astype(np.float64)).labels)
    assert (ParticleClusters().compute(L, pos.tolist()).labels == ref).all()
    assert (ParticleClusters().compute(L, np.asfortranarray(pos)).labels == ref).all()


def test_reading_before_compute_raises_attribute_error():
    for obj, name in [(GridClusters(), "S"), (ParticleClusters(), "labels"),
                      (StructureFactor(), "length"), (PowerLawMle(), "tau"),
                      (SpeedDistribution(), "a2"), (GrowthExponent((1, 10)), "z"),
                      (Msd(), "msd")]:
        with pytest.raises(AttributeError, match="first"):
            getattr(obj, name)


@pytest.mark.parametrize("call, error, words", [
    (lambda: ParticleClusters().compute(10.0, np.zeros((5, 2))), ValueError, "shape"),
    (lambda: ParticleClusters().compute(10.0, np.full((5, 3), np.nan)), ValueError, "finite"),
    (lambda: ParticleClusters().compute(0.0, np.zeros((5, 3))), ValueError, "L must"),
    (lambda: ParticleClusters().compute(-1.0, np.zeros((5, 3))), ValueError, "L must"),
    (lambda: ParticleClusters().compute(10.0, [["a", "b", "c"]]), TypeError, "numbers"),
    (lambda: ParticleClusters().compute(10.0, None), TypeError, "positions"),
    (lambda: ParticleClusters().compute(10.0, np.zeros((0, 3))), ValueError, "at least"),
    (lambda: ParticleClusters(tolerance=-1), ValueError, "tolerance"),
    (lambda: GridClusters(spacing=0), ValueError, "spacing"),
    (lambda: GridClusters(min_fill=2), ValueError, "min_fill"),
    (lambda: GridClusters(assign="x"), ValueError, "assign"),
    (lambda: StructureFactor(k_cut=-1), ValueError, "k_cut"),
    (lambda: StructureFactor().compute(10.0, np.ones((4, 3)), np.ones((3, 3))), ValueError,
     "velocities"),
    (lambda: PowerLawMle(min_tail=1), ValueError, "min_tail"),
    (lambda: PowerLawMle().fit([1, 2, 0]), ValueError, "sizes"),
    (lambda: PowerLawMle().fit([1, 2, 3], [1, 2]), ValueError, "counts"),
    (lambda: GrowthExponent((10, 1)), ValueError, "window"),
    (lambda: GrowthExponent((1, 10)).fit([1, 2, 3], [1, 2]), ValueError, "length"),
    (lambda: Msd(origins="some"), ValueError, "origins"),
    (lambda: SpeedDistribution(bins=0), ValueError, "bins"),
])
def test_bad_input_raises_with_the_argument_named(call, error, words):
    with pytest.raises(error, match=words):
        call()


# ---- power laws, growth, MSD, speeds -------------------------------------------------------

def test_power_law_mle_recovers_tau():
    # 20000 samples of a discrete power law with tau = 2.5 from s = 1 (scipy.stats.zipf): the
    # MLE lies within 4 standard errors of the truth
    from scipy import stats
    samples = stats.zipf.rvs(2.5, size=20000, random_state=11)
    fit = PowerLawMle(min_tail=50).fit(samples)
    assert fit.valid
    assert abs(fit.tau - 2.5) < 4 * fit.tau_err
    s, c = np.unique(samples, return_counts=True)
    hist = PowerLawMle(min_tail=50).fit(s, c)
    assert hist.tau == pytest.approx(fit.tau, rel=1e-9) and hist.s_min == fit.s_min


def test_growth_exponent_of_an_exact_power_law():
    t = np.logspace(0, 3, 31)
    g = GrowthExponent(window=(10, 1000)).fit(t, 3.0 * t ** 1.25)
    assert g.z == pytest.approx(1.25, abs=1e-12)
    assert g.amplitude == pytest.approx(3.0, rel=1e-10)
    finite = np.isfinite(g.local_slope)
    assert np.allclose(g.local_slope[finite], 1.25, atol=1e-12) and finite.sum() > 20
    assert g.regime == "scaling"
    runs = np.array([2.0 * t ** 1.25, 4.0 * t ** 1.25, 3.0 * t ** 1.25])
    gb = GrowthExponent(window=(10, 1000)).fit(t, runs)
    assert gb.z == pytest.approx(1.25, abs=1e-9)


def test_msd_equals_direct_numpy():
    rng = np.random.default_rng(12)
    x = np.cumsum(rng.normal(0, 0.3, (20, 50, 3)), axis=0)
    t = np.arange(20) * 0.5
    first = Msd().compute(t, x)
    assert np.allclose(first.msd, ((x - x[0]) ** 2).sum(axis=2).mean(axis=1), rtol=1e-12)
    allo = Msd(origins="all").compute(t, x)
    direct = [np.mean([((x[i + m] - x[i]) ** 2).sum(axis=1).mean() for i in range(20 - m)])
              for m in range(20)]
    assert np.allclose(allo.msd, direct, rtol=1e-9, atol=1e-12)


def test_speed_distribution_of_a_maxwellian():
    # N = 200000 Gaussian velocities: a2 within 4 of its standard errors of 0, T_g within
    # 4 sqrt(2 / (3 N)) of 1, and every bin that expects at least 25 speeds (where the Poisson
    # count is near normal) within 4 standard deviations, sqrt(f / (N w)) for density f and bin
    # width w, of the Maxwellian at the bin centre (plus 1 % for the centre against the bin's
    # mean of a curved density)
    rng = np.random.default_rng(13)
    v = rng.normal(0, 1, (200000, 3))
    sd = SpeedDistribution().compute(v)
    assert abs(sd.a2) < 4 * sd.a2_err
    assert abs(sd.T_g - 1) < 4 * math.sqrt(2 / (3 * len(v)))
    w = sd.v[1] - sd.v[0]
    sigma = np.sqrt(sd.maxwellian / (len(v) * w))
    filled = len(v) * w * sd.maxwellian >= 25
    assert filled.sum() >= 50
    assert (np.abs(sd.density - sd.maxwellian) < 4 * sigma + 0.01 * sd.maxwellian)[filled].all()
