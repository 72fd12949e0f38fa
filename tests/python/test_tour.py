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


def test_cmake_install_gives_an_importable_package(tmp_path, granagg_bin):
    # cmake --install puts the package in PREFIX/lib/python3.X/dist-packages (Debian's layout
    # for local packages; /usr/local's is on /usr/bin/python3's path)
    build = granagg_bin.parent.parent
    subprocess.run(["cmake", "--install", str(build), "--prefix", str(tmp_path),
                    "--component", "Unspecified"], check=True, capture_output=True)
    site = tmp_path / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / \
        "dist-packages"
    assert (site / "granagg" / "__init__.py").is_file()
    out = subprocess.run([sys.executable, "-c", "import granagg; print(granagg.__file__)"],
                         env={"PYTHONPATH": str(site), "PATH": "/usr/bin:/bin"}, check=True,
                         capture_output=True, text=True, cwd=tmp_path).stdout
    assert out.strip() == str(site / "granagg" / "__init__.py")
