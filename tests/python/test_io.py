"""granagg.io against h5py's and pandas' reading of the same files."""
import h5py
import numpy as np
import pandas as pd
import pytest

from granagg import io


def test_read_trajectory_equals_h5py(cli_run):
    frames = list(io.read_trajectory(cli_run))
    with h5py.File(cli_run / "traj.h5", "r") as f:
        part = f["particles/all"]
        pos = part["position/value"][()]
        vel = part["velocity/value"][()]
        img = part["image/value"][()]
        times = part["box/edges/time"][()]  # the frames' times and steps, shared by all elements
        steps = part["box/edges/step"][()]
        box = part["box/edges/value"][()]
        charges = part["charge/value"][()]
    assert len(frames) == len(times) > 3
    for k, fr in enumerate(frames):
        assert fr.time == times[k] and fr.step == steps[k] and fr.index == k
        assert np.array_equal(fr.positions, pos[k])
        assert np.array_equal(fr.velocities, vel[k])
        assert np.array_equal(fr.images, img[k])
        assert fr.box == np.ravel(box[k])[0]
        assert np.array_equal(fr.charges, charges[k])
        assert not fr.positions.flags.writeable


def test_read_trajectory_errors():
    with pytest.raises(ValueError, match="no file"):
        io.read_trajectory("/nonexistent/traj.h5")


def test_read_table_equals_pandas(tmp_path, granagg_bin):
    import subprocess
    out = tmp_path / "haff.csv"
    subprocess.run([str(granagg_bin), "kinetic", "haff", "--out", str(out)], check=True)
    df = io.read_table(out)
    ref = pd.read_csv(out, comment="#", float_precision="round_trip")
    pd.testing.assert_frame_equal(df, ref, check_exact=True)
    assert df.attrs["eps"] == "0.9" and "granagg" in " ".join(df.attrs.values())
    with pytest.raises(ValueError, match="no file"):
        io.read_table(tmp_path / "missing.csv")
