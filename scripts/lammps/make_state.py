#!/usr/bin/python3
"""Benchmark initial state, shared by bench_md_lammps.sh and bench_coulomb_lammps.sh.

    make_state.py N PHI OUTDIR [--charged]

Writes OUTDIR/state_N.csv (granagg: x,y,z,vx,vy,vz[,q]) and OUTDIR/state_N.data (LAMMPS data file:
atom_style sphere, or hybrid sphere charge with --charged) holding the same state: random
non-overlapping unit spheres at filling fraction PHI (random sequential addition on a cell list),
Gaussian velocities with zero momentum rescaled to T_g = (1/3N) sum v^2 = 1 exactly, like granagg's
own random state; with --charged, a random half +1 and the other half -1 (zero net charge; for odd
N one particle stays neutral). Density 6/pi gives mass 1 at diameter 1.
"""
import math
import random
import sys

N, phi, out = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
charged = "--charged" in sys.argv[4:]
L = (N * math.pi / (6 * phi)) ** (1 / 3)
rng = random.Random(12345)
nc = int(L)  # cells of edge >= 1 (= diameter)
cl = L / nc
cells = {}
pos = []
while len(pos) < N:
    p = (rng.random() * L, rng.random() * L, rng.random() * L)
    c = [int(p[k] / cl) % nc for k in range(3)]
    ok = True
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dz in (-1, 0, 1):
                for j in cells.get(((c[0] + dx) % nc, (c[1] + dy) % nc, (c[2] + dz) % nc), ()):
                    q = pos[j]
                    r2 = 0.0
                    for k in range(3):
                        d = p[k] - q[k]
                        d -= L * round(d / L)
                        r2 += d * d
                    if r2 < 1.0:
                        ok = False
                        break
                if not ok:
                    break
            if not ok:
                break
        if not ok:
            break
    if ok:
        cells.setdefault(tuple(c), []).append(len(pos))
        pos.append(p)
vel = [[rng.gauss(0, 1) for _ in range(3)] for _ in range(N)]
mean = [sum(v[k] for v in vel) / N for k in range(3)]
vel = [[v[k] - mean[k] for k in range(3)] for v in vel]
s = math.sqrt(1.0 / (sum(v[0] ** 2 + v[1] ** 2 + v[2] ** 2 for v in vel) / (3 * N)))
vel = [[x * s for x in v] for v in vel]
charges = None
if charged:
    charges = [1] * (N // 2) + [-1] * (N // 2) + [0] * (N % 2)
    rng.shuffle(charges)

with open(f"{out}/state_{N}.csv", "w") as f:
    f.write("x,y,z,vx,vy,vz" + (",q" if charged else "") + "\n")
    for i, (p, v) in enumerate(zip(pos, vel)):
        f.write(",".join(repr(x) for x in (*p, *v)) + (f",{charges[i]}" if charged else "") + "\n")
with open(f"{out}/state_{N}.data", "w") as f:
    kind = "charged " if charged else ""
    f.write(f"granagg {kind}benchmark state, N = {N}, phi = {phi}\n\n{N} atoms\n1 atom types\n\n")
    for a in "xyz":
        f.write(f"0.0 {L!r} {a}lo {a}hi\n")
    if charged:
        f.write("\nAtoms # hybrid\n\n")
        for i, (p, q) in enumerate(zip(pos, charges)):
            f.write(f"{i + 1} 1 {p[0]!r} {p[1]!r} {p[2]!r} 1.0 {6 / math.pi!r} {q}\n")
    else:
        f.write("\nAtoms # sphere\n\n")
        for i, p in enumerate(pos):
            f.write(f"{i + 1} 1 1.0 {6 / math.pi!r} {p[0]!r} {p[1]!r} {p[2]!r}\n")
    f.write("\nVelocities\n\n")
    for i, v in enumerate(vel):
        f.write(f"{i + 1} {v[0]!r} {v[1]!r} {v[2]!r} 0 0 0\n")
