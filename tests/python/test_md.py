"""granagg.md: a run driven from Python against `granagg md` (bit for bit), callbacks, Ctrl-C,
exceptions in callbacks, the GIL and configuration errors."""
import os
import signal
import threading
import time

import h5py
import numpy as np
import pytest

import granagg
from granagg.md import Simulation

from conftest import SMALL


def frames_of(run):
    with h5py.File(run / "traj.h5", "r") as f:
        part = f["particles/all"]
        return {name: part[name + "/value"][()]
                for name in ("position", "velocity", "image", "charge")}, \
            part["box/edges/time"][()]


def observables_of(run):
    with h5py.File(run / "traj.h5", "r") as f:
        g = f["granagg/observables"]
        return {k: g[k]["value"][()] for k in g.keys()}


def assert_same_run(a, b):
    fa, ta = frames_of(a)
    fb, tb = frames_of(b)
    assert np.array_equal(ta, tb)
    for name in fa:
        assert np.array_equal(fa[name], fb[name]), name
    oa, ob = observables_of(a), observables_of(b)
    assert oa.keys() == ob.keys()
    for k in oa:
        assert np.array_equal(oa[k], ob[k], equal_nan=True), k


def test_python_run_is_bit_identical_to_granagg_md(cli_run, tmp_path):
    with Simulation("quick", overrides=SMALL, out=tmp_path / "py") as sim:
        summary = sim.run()
        assert not summary["stopped"] and sim.time == pytest.approx(3.0, abs=0.01)
    assert_same_run(cli_run, tmp_path / "py")


def test_callbacks_fire_on_schedule_and_change_no_bit(cli_run, tmp_path):
    steps, frame_times, seen = [], [], {}

    def every7(state):
        steps.append(state.step)
        if "positions" not in seen:
            seen["positions"] = state.positions
            seen["state"] = state
            assert state.positions.shape == (400, 3) and not state.positions.flags.writeable
            assert ((state.positions >= 0) & (state.positions < state.box)).all()

    def at_frames(state):
        assert state.at_frame
        frame_times.append(state.time)

    with Simulation("quick", overrides=SMALL, out=tmp_path / "cb") as sim:
        sim.run(callbacks=[(7, every7), ("frames", at_frames)])
        last = sim.step
        assert len(sim.observables) >= last // 100
        assert (np.diff(sim.observables["step"]) > 0).all()
    assert steps == list(range(7, last + 1, 7))
    _, times = frames_of(tmp_path / "cb")
    assert np.allclose(frame_times, times[1:])  # the frame at t = 0 is written before run()
    with pytest.raises(AttributeError, match="during its callback"):
        seen["state"].positions  # a state kept past its call refuses to be read
    assert seen["positions"].shape == (400, 3)  # arrays taken during the call stay valid
    assert_same_run(cli_run, tmp_path / "cb")


def test_an_exception_in_a_callback_stops_with_a_checkpoint_and_reaches_the_caller(
        cli_run, tmp_path):
    out = tmp_path / "raise"

    def fail(state):
        if state.step >= 300:
            raise RuntimeError("stop here")

    sim = Simulation("quick", overrides=SMALL, out=out)
    with pytest.raises(RuntimeError, match="stop here"):
        sim.run(callbacks=[(50, fail)])
    assert (out / "checkpoint.h5").is_file()
    assert 300 <= sim.step < 400
    sim.run()  # continues from the checkpoint to the end
    sim.close()
    assert_same_run(cli_run, out)


def test_ctrl_c_stops_the_run_cleanly_and_it_continues(cli_run, tmp_path):
    out = tmp_path / "sigint"
    sim = Simulation("quick", overrides=dict(SMALL, **{"run.t_end": 3.0}), out=out)
    calls, at_signal = [], []

    def interrupt():
        at_signal.append(calls[-1] if calls else 0)
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(0.3, interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        # a slow callback makes the run last long enough to be interrupted
        sim.run(callbacks=[(1, lambda s: (calls.append(s.step), time.sleep(0.002)))])
    timer.join()
    # Stopped at the chunk after the signal (a callback every step: chunks of one step), counted in
    # steps rather than seconds, so that a loaded machine cannot fail it.
    assert at_signal[0] <= sim.step <= at_signal[0] + 3
    assert (out / "checkpoint.h5").is_file() and sim.step < 900
    sim.run()
    sim.close()
    assert_same_run(cli_run, out)


def test_the_gil_is_released_while_cpp_runs(tmp_path):
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(1)
            time.sleep(0.001)

    worker = threading.Thread(target=count)
    with Simulation("quick", overrides=dict(SMALL, **{"run.t_end": 3.0})) as sim:
        worker.start()
        t0 = time.monotonic()
        sim.run()
        elapsed = time.monotonic() - t0
        stop.set()
        worker.join()
        assert sim.folder is None  # out=None: a private temporary folder
    # the worker thread ran during the C++ loop: at least a tick per 10 ms of run
    assert len(ticks) > elapsed / 0.01


def test_restart_and_run_further(tmp_path):
    out = tmp_path / "restart"
    with Simulation("quick", overrides=dict(SMALL, **{"run.t_end": 1.0}), out=out) as sim:
        sim.run()
    with Simulation.restart(out) as sim:
        assert sim.time == pytest.approx(1.0, abs=0.01)
        sim.run(t_end=2.0)
        assert sim.time == pytest.approx(2.0, abs=0.01)
        sim.checkpoint()
        frame = sim.frame
        assert frame["positions"].shape == (400, 3)


@pytest.mark.parametrize("config, overrides, error, words", [
    ("quick", {"system.Nn": 10}, ValueError, "system.Nn"),
    ("quick", {"system.phi": 0.9}, ValueError, "system.phi"),
    ({"system": {"N": 1}}, None, ValueError, "system.N"),
    ({"sistem": {"N": 100}}, None, ValueError, "sistem"),
    ("nopreset", None, ValueError, "no preset named"),
    ("/no/such/file.toml", None, ValueError, "no file"),
    (42, None, TypeError, "config"),
    ("quick", {"system.N": [1, 2]}, TypeError, "system.N"),
])
def test_bad_configuration_raises_with_the_cli_message(config, overrides, error, words):
    with pytest.raises(error, match=words):
        Simulation(config, overrides=overrides)


def test_config_error_names_the_key():
    with pytest.raises(granagg.ConfigError) as e:
        Simulation("quick", overrides={"system.phi": 0.9})
    assert e.value.key == "system.phi"


def test_bad_run_arguments(tmp_path):
    with Simulation("quick", overrides=SMALL) as sim:
        with pytest.raises(ValueError, match="every"):
            sim.run(callbacks=[(0, print)])
        with pytest.raises(TypeError, match="pairs"):
            sim.run(callbacks=[(5,)])
        with pytest.raises(ValueError, match="t_end"):
            sim.run(t_end=-1.0)
    with pytest.raises(ValueError, match="closed"):
        sim.run()
