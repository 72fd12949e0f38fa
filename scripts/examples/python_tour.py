"""The Python tour of granagg (docs/python.md): run a small gas from Python, compute its
clusters and density length l(t) in a callback, solve the Smoluchowski equation, and plot S(t)
from both on one figure.

    PYTHONPATH=build/python /usr/bin/python3 scripts/examples/python_tour.py [OUT_DIR]

Writes OUT_DIR/tour.png and OUT_DIR/tour.csv (default: tour-out). About 10 s on 2 cores.
"""
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")  # a file, no window (drop this line in a notebook)
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

import granagg
from granagg.analysis import GridClusters, ParticleClusters, StructureFactor
from granagg.md import Simulation

out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "tour-out")
out.mkdir(parents=True, exist_ok=True)

# 1. A small charged gas: the quick preset (Hertz contacts, phi = 0.076) with the paper's
#    charged settings K = 5, Q = 0.05 (docs/model.md), 1000 particles, to t = 60.
grid = GridClusters(spacing=2.0, min_fill=0.25)
contact = ParticleClusters(tolerance=0.05)
sk = StructureFactor()
rows = []


def analyse(state):
    """At every frame time: grid and contact clusters, and the density length l."""
    grid.compute(state.box, state.positions)
    contact.compute(state.box, state.positions)
    sk.compute(state.box, state.positions)
    rows.append({"t": state.time, "S_grid": grid.S, "S_particle": contact.S,
                 "largest_share": contact.largest_share, "l_density": sk.length})


settings = {"system.N": 1000, "run.t_end": 60.0, "system.seed": 4, "coulomb.K": 5.0,
            "charging.Q": 0.05}
with Simulation("quick", overrides=settings) as sim:
    sim.run(callbacks=[("frames", analyse)])
    temperature = sim.observables[["t", "T_g"]]

md = pd.DataFrame(rows)
md.to_csv(out / "tour.csv", index=False)
print(md.tail(3).to_string(index=False))

# 2. The Smoluchowski equation with the paper's kernel exponent beta = 2 (sectional method).
mf = granagg.meanfield.smoluchowski(beta=2.0, t_end=60.0)

# 3. S(t) from both on one figure (the mean field in its own time unit: its curve shows the
#    shape, not a fit; granagg.meanfield.fit_beta fits the two).
fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
a.loglog(md["t"][1:], md["S_particle"][1:], "o-", label="MD: contact clusters S")
a.loglog(md["t"][1:], md["S_grid"][1:], "s-", label="MD: grid clusters S")
a.loglog(mf.t, mf.S, "k--", label=r"Smoluchowski, $\beta = 2$ (t in $1/(K_0 n_1)$)")
a.set_xlabel("t")
a.set_ylabel("S(t)")
a.legend(fontsize=8)
b.semilogx(md["t"][1:], md["l_density"][1:], "o-", label=r"density length $l$")
b.set_xlabel("t")
b.set_ylabel("l [d]")
b2 = b.twinx()
b2.loglog(temperature["t"][1:], temperature["T_g"][1:], "r-", lw=1, label=r"$T_g$")
b2.set_ylabel(r"$T_g$", color="r")
b.legend(fontsize=8, loc="upper left")
b2.legend(fontsize=8, loc="lower right")
fig.tight_layout()
fig.savefig(out / "tour.png", dpi=120)
print(f"wrote {out / 'tour.png'} and {out / 'tour.csv'}")
