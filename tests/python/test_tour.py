"""The example of docs/python.md runs as it is (Agg backend) and writes its figure."""
import pathlib
import subprocess
import sys

import pandas as pd

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_python_tour_runs(tmp_path):
    subprocess.run([sys.executable, str(ROOT / "scripts" / "examples" / "python_tour.py"),
                    str(tmp_path)], check=True, cwd=tmp_path)
    assert (tmp_path / "tour.png").stat().st_size > 10000
    md = pd.read_csv(tmp_path / "tour.csv")
    assert len(md) > 10 and (md["S_particle"] >= 1).all() and md["l_density"].notna().all()
