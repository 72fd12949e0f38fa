"""Shared fixtures of the Python package's tests (docs/python.md).

Run from a folder outside the source tree, with the built package on PYTHONPATH
(scripts/test.sh does): PYTHONPATH=build/python /usr/bin/python3 -m pytest tests/python.
GRANAGG_BIN names the granagg executable of the same build (default build/bin/granagg).
"""
import os
import pathlib
import subprocess

import pytest

import granagg

ROOT = pathlib.Path(__file__).resolve().parents[2]


def pytest_report_header(config):
    return f"granagg {granagg.__version__} from {pathlib.Path(granagg.__file__).parent}"


@pytest.fixture(scope="session")
def granagg_bin():
    path = pathlib.Path(os.environ.get("GRANAGG_BIN", ROOT / "build" / "bin" / "granagg"))
    assert path.is_file(), f"no granagg executable at {path} (set GRANAGG_BIN)"
    return path


# A small neutral gas: the quick preset with fewer particles, to t = 3 (a few hundred steps),
# frames 10 per decade, velocities stored.
SMALL = {"system.N": 400, "run.t_end": 3.0, "output.frames_per_decade": 10}


def small_sets(extra=None):
    sets = dict(SMALL, **(extra or {}))
    args = []
    for k, v in sets.items():
        args += ["--set", f"{k}={v}"]
    return sets, args


@pytest.fixture(scope="session")
def cli_run(granagg_bin, tmp_path_factory):
    """The small gas run by `granagg md` (the reference of the Python-driven runs)."""
    out = tmp_path_factory.mktemp("cli") / "run"
    _, args = small_sets()
    subprocess.run([str(granagg_bin), "md", "--preset", "quick", "--quiet", "--out", str(out)]
                   + args, check=True)
    return out
