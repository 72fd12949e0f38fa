"""granagg: aggregation in charged granular gases, from Python.

The package binds granagg's C++ libraries (docs/python.md); nothing here is a second
implementation:

- granagg.analysis: per-frame compute objects in freud's style (GridClusters,
  ParticleClusters, StructureFactor, PowerLawMle, Msd, SpeedDistribution, GrowthExponent);
- granagg.meanfield: smoluchowski(), kinetic(), fit_beta();
- granagg.io: read_trajectory(), read_table();
- granagg.md: Simulation, an MD run driven from Python with callbacks.

Units are docs/model.md's: d = m = T0 = 1.
"""
from . import _granagg
from ._granagg import ConfigError, __version__, analysis, io, md, meanfield

__all__ = ["analysis", "io", "md", "meanfield", "ConfigError", "__version__"]

# `import granagg.analysis` and `from granagg.md import Simulation` find the submodules of the
# extension module.
import sys as _sys

for _name in ("analysis", "io", "md", "meanfield"):
    _sys.modules[__name__ + "." + _name] = getattr(_granagg, _name)
del _sys, _name
