"""The Python examples (examples/python/) run and say what they should."""
import os
import re
import subprocess
import sys

from conftest import SOURCE

EXAMPLES = os.path.join(SOURCE, "examples", "python")


def run(name, *args):
    r = subprocess.run([sys.executable, os.path.join(EXAMPLES, name), *map(str, args)], capture_output=True,
                       text=True, env=dict(os.environ, MPLBACKEND="Agg"))
    assert r.returncode == 0, r.stderr
    return r.stdout


def test_estimate_and_plot(tmp_path):
    out = run("estimate_and_plot.py", tmp_path / "depths.png")
    assert "30 of 30 points ok" in out
    assert (tmp_path / "depths.png").stat().st_size > 10000


def test_servo_loop():
    out = run("servo_loop.py")
    last = out.strip().splitlines()[-1]
    depths = [float(x) for x in re.findall(r"(\d\.\d+)\*", last)]
    truth = [float(x) for x in last.split("truth")[1].split()]
    assert len(depths) == 4, last  # every depth converged
    assert all(abs(d - t) < 0.02 for d, t in zip(depths, truth)), last


def test_measure_folder(tmp_path):
    """The folder of rendered images measured by the example gives `yawdepth measure`'s points file."""
    from conftest import CALIB, run_cli, simulate
    scene = simulate(str(tmp_path / "scene"), "--frames", 6, "--pattern", "chessboard:7x5:0.02", "--supersampling", 2,
                     "--step", 0.01)
    out = run("measure_folder.py", scene["camera"], scene["rig"], scene["motion"], "chessboard:7x5:0.02",
              tmp_path / "py.csv", "exact")
    assert "210 observations of 35 features in 6 images" in out, out
    run_cli("measure", "--camera", scene["camera"], "--rig", scene["rig"], "--motion", scene["motion"], "--pattern",
            "chessboard:7x5:0.02", "--method", "exact", "--out", tmp_path / "cli.csv", "--quiet")
    assert (tmp_path / "py.csv").read_text() == (tmp_path / "cli.csv").read_text()
