"""Shared fixtures: the command line (YAWDEPTH_CLI, set by the ctest entry) and scenes it simulates."""
import os
import subprocess

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))
CALIB = os.environ.get("YAWDEPTH_CALIB_DIR", os.path.join(SOURCE, "calib"))


def cli_path():
    path = os.environ.get("YAWDEPTH_CLI")
    if not path:
        pytest.fail("YAWDEPTH_CLI is not set: run the suite through ctest (python_pytest), or set it to the "
                    "built tools/yawdepth")
    return path


def run_cli(*args, check=True):
    """Run `yawdepth ARGS`; returns the CompletedProcess (text)."""
    r = subprocess.run([cli_path(), *map(str, args)], capture_output=True, text=True)
    if check and r.returncode != 0:
        raise AssertionError(f"yawdepth {' '.join(map(str, args))} failed: {r.stderr}")
    return r


def simulate(out_dir, *extra):
    """A simulated sequence in out_dir (motion.csv, tracks.csv, truth.csv) with the paper's camera and rig."""
    run_cli("simulate", "--camera", os.path.join(CALIB, "paper_camera.yaml"), "--rig",
            os.path.join(CALIB, "paper_rig.yaml"), "--out-dir", out_dir, *extra)
    return {"camera": os.path.join(CALIB, "paper_camera.yaml"), "rig": os.path.join(CALIB, "paper_rig.yaml"),
            "motion": os.path.join(out_dir, "motion.csv"), "tracks": os.path.join(out_dir, "tracks.csv"),
            "dir": out_dir}


@pytest.fixture(scope="session")
def planar_scene(tmp_path_factory):
    """30 points x 10 frames, a turning robot with a panning camera, noisy pixels and odometry."""
    d = str(tmp_path_factory.mktemp("planar"))
    return simulate(d, "--frames", 10, "--points", 30, "--step", 0.03, "--yaw-rate", 0.01, "--turn-rate", 0.005,
                    "--sigma-px", 0.3, "--sigma-odom", 0.0005, "--seed", 7)


@pytest.fixture(scope="session")
def arm_scene(tmp_path_factory):
    """A 6-DoF arm orbiting its target (the 6-DoF motion columns)."""
    d = str(tmp_path_factory.mktemp("arm"))
    return simulate(d, "--frames", 12, "--points", 20, "--arm", "orbit", "--sigma-px", 0.2, "--seed", 3)


def assert_points_equal(a, b):
    """Two structured points arrays hold the same values (NaN equal to NaN: the numbers of a point
    that is not ok)."""
    import numpy as np
    assert a.dtype == b.dtype and a.shape == b.shape
    for name in a.dtype.names:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)
