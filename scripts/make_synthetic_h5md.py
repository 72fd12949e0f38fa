#!/usr/bin/python3
"""Writes a synthetic H5MD 1.1 trajectory for benchmarking `granagg analyze` \
(scripts/bench_analysis.sh).

N particles at filling fraction phi in a cubic periodic box, Maxwell velocities (T = 1), ballistic
motion (positions wrapped with image counts), small random charges, F log-spaced frames. A
fraction of the particles sits in compact blobs so that grid and particle clusters exist. The
layout is the one `granagg md` writes (/particles/all/{position,image,velocity,charge,box/edges}).

    make_synthetic_h5md.py OUT.h5 [N] [FRAMES] [SPACING] [SEED]

SPACING: log (default; t = 0 and 1e-2 .. 1e3) or linear (t = 0, 5, 10, ...: the all-origins MSD
applies).
"""
import sys

import h5py
import numpy as np


def main():
    out = sys.argv[1]
    n = int(float(sys.argv[2])) if len(sys.argv) > 2 else 100000
    frames = int(sys.argv[3]) if len(sys.argv) > 3 else 200
    spacing = sys.argv[4] if len(sys.argv) > 4 else "log"
    seed = int(sys.argv[5]) if len(sys.argv) > 5 else 1
    phi = 0.076
    L = (n * np.pi / (6 * phi)) ** (1 / 3)
    rng = np.random.default_rng(seed)
    x0 = rng.uniform(0, L, (n, 3))
    # 20 % of the particles in blobs of 50 on a simple cubic lattice of spacing 1.02 (bonded)
    blob = 50
    nb = int(0.2 * n) // blob
    side = int(np.ceil(blob ** (1 / 3)))
    lattice = 1.02 * np.array([(i, j, k) for i in range(side) for j in range(side)
                               for k in range(side)])[:blob]
    for b in range(nb):
        x0[b * blob:(b + 1) * blob] = rng.uniform(0, L, 3) + lattice
    v = rng.normal(0, 1, (n, 3))
    # blobs move rigidly
    v[: nb * blob] = np.repeat(rng.normal(0, 1 / np.sqrt(blob), (nb, 3)), blob, axis=0)
    q = rng.normal(0, 0.1, n)
    if spacing == "linear":
        times = 5.0 * np.arange(frames)
    else:
        times = np.concatenate([[0.0], np.logspace(-2, 3, frames - 1)])
    with h5py.File(out, "w") as f:
        f.create_group("h5md").attrs["version"] = np.array([1, 1], dtype=np.int32)
        part = f.create_group("particles/all")
        chunks = lambda *inner: (1,) + inner
        pos = part.create_dataset("position/value", (frames, n, 3), "f8", chunks=chunks(n, 3))
        img = part.create_dataset("image/value", (frames, n, 3), "i4", chunks=chunks(n, 3))
        vel = part.create_dataset("velocity/value", (frames, n, 3), "f8", chunks=chunks(n, 3))
        chg = part.create_dataset("charge/value", (frames, n), "f8", chunks=chunks(n))
        edges = part.create_dataset("box/edges/value", (frames, 3, 3), "f8")
        part["box"].attrs["dimension"] = 3
        part["position/step"] = np.arange(frames, dtype=np.int64) * 100
        part["position/time"] = times
        for name in ("image", "velocity", "charge", "box/edges"):
            part[name + "/step"] = part["position/step"]
            part[name + "/time"] = part["position/time"]
        for k, t in enumerate(times):
            u = x0 + v * t
            im = np.floor(u / L)
            pos[k] = u - im * L
            img[k] = im.astype(np.int32)
            vel[k] = v
            chg[k] = q * (1 + np.log1p(t))
            edges[k] = np.diag([L, L, L])
        f.create_group("parameters").attrs["charging.kappa"] = "0.83"
    print(f"wrote {out}: N = {n}, {frames} frames, L = {L:.4g}")


if __name__ == "__main__":
    main()
