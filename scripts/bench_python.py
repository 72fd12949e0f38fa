"""Benchmarks of the Python package (docs/benchmarks.md, "Python package"; issue 46):

1. the call and conversion overhead of ParticleClusters, GridClusters and StructureFactor at
   N = 1e5 beside the same C++ call timed inside the module (granagg.analysis._time_cpp), both in
   this process on the same positions and threads (best of REPEATS each, interleaved);
2. the SciPy way of computing the same (Debian has no freud): cKDTree(boxsize) +
   connected_components, scipy.ndimage.label with periodic merging, numpy.fft for S(k);
3. a run with a no-op callback every 100 steps beside the same run without (best of 3,
   interleaved; the quick preset at N = 4000 to t = 100).

    PYTHONPATH=build/python /usr/bin/python3 scripts/bench_python.py [--threads 2]

Prints a Markdown table per part; nothing is written.
"""
import argparse
import os
import time

import numpy as np

REPEATS = 5


def best(fn, repeats=REPEATS):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def clustered(L, N, seed):
    """Positions with aggregates (Gaussian blobs of 50) over a uniform gas, as a late gas."""
    rng = np.random.default_rng(seed)
    n_blob = N // 2
    centres = rng.uniform(0, L, (n_blob // 50, 3)).repeat(50, axis=0)
    blob = centres + rng.normal(0, 1.2, (len(centres), 3))
    gas = rng.uniform(0, L, (N - len(blob), 3))
    return np.mod(np.concatenate([blob, gas]), L)


def scipy_particle_clusters(L, pos, tol=0.05):
    from scipy import sparse
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree
    pairs = cKDTree(pos, boxsize=L).query_pairs(1 + tol, output_type="ndarray")
    g = sparse.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])),
                          shape=(len(pos), len(pos)))
    return connected_components(g, directed=False)


def scipy_grid_clusters(L, pos, spacing=2.0, min_count=4):
    from scipy import ndimage
    from scipy.sparse.csgraph import connected_components
    from scipy import sparse
    n = int(L // spacing)
    idx = np.minimum((pos / (L / n)).astype(int), n - 1)
    counts = np.zeros((n, n, n))
    np.add.at(counts, tuple(idx.T), 1)
    labels, k = ndimage.label(counts >= min_count)
    a, b = [], []
    for axis in range(3):  # periodic merging: labels facing each other across a face
        first, last = np.take(labels, 0, axis).ravel(), np.take(labels, -1, axis).ravel()
        both = (first > 0) & (last > 0)
        a.append(first[both])
        b.append(last[both])
    a, b = np.concatenate(a), np.concatenate(b)
    g = sparse.coo_matrix((np.ones(len(a)), (a, b)), shape=(k + 1, k + 1))
    return connected_components(g, directed=False)


def numpy_structure_factor(L, pos, h=0.5):
    M = int(np.ceil(L / h))
    rho, _ = np.histogramdd(pos, bins=(M, M, M), range=[(0, L)] * 3)  # NGP (numpy has no CIC)
    f = np.fft.rfftn(rho)
    return np.abs(f) ** 2 / len(pos)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--threads", type=int, default=0, help="OMP_NUM_THREADS (0: as set)")
    ap.add_argument("--N", type=int, default=100000)
    args = ap.parse_args()
    if args.threads:
        os.environ["OMP_NUM_THREADS"] = str(args.threads)
    import granagg
    from granagg import analysis
    from granagg.md import Simulation

    N = args.N
    L = (N * np.pi / (6 * 0.076)) ** (1 / 3)
    pos = clustered(L, N, 1)
    print(f"{granagg.__version__}; N = {N}, L = {L:.2f}, phi = 0.076 (half the "
          f"particles in blobs of 50); OMP_NUM_THREADS = {os.environ.get('OMP_NUM_THREADS')}")

    print("\n| compute | C++ call [ms] | Python call [ms] | overhead | SciPy way [ms] |")
    print("|---|---|---|---|---|")
    objects = {"ParticleClusters": (analysis.ParticleClusters(),
                                    lambda: scipy_particle_clusters(L, pos)),
               "GridClusters": (analysis.GridClusters(), lambda: scipy_grid_clusters(L, pos)),
               "StructureFactor": (analysis.StructureFactor(),
                                   lambda: numpy_structure_factor(L, pos))}
    for name, (obj, scipy_way) in objects.items():
        obj.compute(L, pos)  # warm: the mesh, the pages
        cpp, py = [], []
        for _ in range(REPEATS):  # interleaved, so that a slow spell hits both
            cpp.append(min(analysis._time_cpp(name, L, pos, 2)[1:]))  # (the 1st makes the mesh)
            t0 = time.perf_counter()
            obj.compute(L, pos)
            py.append(time.perf_counter() - t0)
        sp = best(scipy_way, 3)
        c, p = min(cpp), min(py)
        print(f"| {name} | {1e3 * c:.1f} | {1e3 * p:.1f} | {100 * (p / c - 1):+.1f} % | "
              f"{1e3 * sp:.1f} |")

    settings = {"system.N": 4000, "run.t_end": 100.0, "system.seed": 3}
    calls = []

    def run(callback):
        with Simulation("quick", overrides=settings) as sim:
            cbs = [(100, callback)] if callback else None
            t0 = time.perf_counter()
            sim.run(callbacks=cbs)
            return time.perf_counter() - t0, sim.step

    plain, with_cb = [], []
    for _ in range(3):
        plain.append(run(None)[0])
        t, steps = run(lambda s: calls.append(s.step))
        with_cb.append(t)
    print(f"\n| run (quick, N = 4000, t = 100, {steps} steps) | best of 3 [s] |")
    print("|---|---|")
    print(f"| no callback | {min(plain):.3f} |")
    print(f"| no-op callback every 100 steps | {min(with_cb):.3f} "
          f"({100 * (min(with_cb) / min(plain) - 1):+.1f} %) |")


if __name__ == "__main__":
    main()
