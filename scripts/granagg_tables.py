"""Reading granagg's tables from Python (plots and checks only; the numbers come from granagg).

granagg writes CSV tables with '# key = value' provenance lines, then one header row
(docs/analysis.md). `read(path)` returns a numpy structured array (None when the file is absent
or has no rows); `meta(path)` returns the provenance as a dict; `col(table, name)` a column or None;
`paper()` the paper's published values (data/reference/paper.json, the one place they are typed).
Needs Debian's python3-numpy (/usr/bin/python3).
"""
import io
import json
import os

import numpy as np


def read(path):
    """A granagg CSV table as a numpy structured array (None if absent or empty); '#' lines
    dropped."""
    if not os.path.exists(path):
        return None
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    if len(lines) < 2:
        return None
    a = np.genfromtxt(io.StringIO("".join(lines)), delimiter=",", names=True)
    return np.atleast_1d(a)


def meta(path):
    """The '# key = value' provenance lines of a granagg CSV as a dict (empty if absent)."""
    out = {}
    if not os.path.exists(path):
        return out
    with open(path) as f:
        for line in f:
            if not line.startswith("#"):
                break
            if " = " in line:
                k, v = line[1:].strip().split(" = ", 1)
                out[k.strip()] = v.strip()
    return out


def col(tab, name):
    """Column `name` of a table, or None when the table or the column is missing."""
    return tab[name] if tab is not None and name in tab.dtype.names else None


def load_json(path):
    """A JSON file as a dict (empty if absent)."""
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return json.load(f)


def paper():
    """The paper's published values (Singh & Mazza 2018) from data/reference/paper.json, as a
    dict (e.g. paper()["z_neutral"]["value"]); C++ reads the same file (common/PaperValues.h)."""
    here = os.path.dirname(os.path.abspath(__file__))
    with open(os.path.join(here, "..", "data", "reference", "paper.json")) as f:
        return json.load(f)
