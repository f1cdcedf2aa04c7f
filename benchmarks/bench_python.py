#!/usr/bin/python3
"""The Python module's cost beside the C++ call on the same input (docs/python.md, "Cost").

    /usr/bin/python3 benchmarks/bench_python.py [--build DIR] [--repeats N]

Needs the build tree's Python module (DIR/python), command line (DIR/tools/yawdepth, to simulate the
inputs) and C++ harness (DIR/benchmarks/bench_python_cost: cmake --build DIR --target
bench_python_cost). Two cases, as issue #33 states them, medians over the repeats:
  - estimatePoints of 30 points x 10 frames (the default method, fused; exact shown too): the Python
    call (arrays in, conversion, the C++ call, the structured points array out) against the C++
    estimatePoints() on the same files; target: under 10 % above the C++ call;
  - DepthProvider.updateOdometry with 4 features per period (200 periods, per update): target under
    20 microseconds added per update.
Each figure is the least of the rounds' medians, the C++ harness and Python taking turns.
Prints a Markdown table; exits 1 when a target is missed.
"""
import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

here = os.path.dirname(os.path.abspath(__file__))
source = os.path.dirname(here)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(source, "build"))
    ap.add_argument("--repeats", type=int, default=1000)
    ap.add_argument("--rounds", type=int, default=5)
    a = ap.parse_args()
    sys.path.insert(0, os.path.join(a.build, "python"))
    import yawdepth  # noqa: E402

    cli = os.path.join(a.build, "tools", "yawdepth")
    harness = os.path.join(a.build, "benchmarks", "bench_python_cost")
    camera_file = os.path.join(source, "calib", "paper_camera.yaml")
    rig_path = os.path.join(source, "calib", "paper_rig.yaml")
    tmp = tempfile.mkdtemp(prefix="bench_python_", dir=a.build)

    def scene(name, *extra):
        d = os.path.join(tmp, name)
        subprocess.run([cli, "simulate", "--camera", camera_file, "--rig", rig_path, "--out-dir", d, *extra],
                       check=True, capture_output=True)
        return os.path.join(d, "motion.csv"), os.path.join(d, "tracks.csv")

    def cxx(*args):
        out = subprocess.run([harness, *map(str, args)], check=True, capture_output=True, text=True).stdout
        return float(out)

    camera = yawdepth.loadCameraFile(camera_file)
    rig_file = yawdepth.readRigFile(rig_path)
    rig = rig_file.rig()

    def load(motion_path, tracks_path):
        motion = yawdepth.readMotionCsv(motion_path, rig_file.yaw)
        yawdepth.applyRigFile(rig_file, motion)
        return motion, yawdepth.readTracksCsv(tracks_path)

    def rounds(cxx_round, python_round):
        """(C++, Python): the least of the rounds' medians, the two taking turns."""
        c, p = [], []
        for _ in range(a.rounds):
            c.append(cxx_round())
            p.append(python_round())
        return min(c), min(p)

    rows = []
    missed = False
    # estimate: 30 points x 10 frames
    m_path, t_path = scene("estimate", "--frames", "10", "--points", "30", "--sigma-px", "0.3", "--seed", "5")
    motion, tracks = load(m_path, t_path)
    for method, target in (("fused", True), ("exact", False)):
        def python_round():
            times = []
            for _ in range(a.repeats):
                t0 = time.perf_counter()
                yawdepth.estimatePoints(camera, rig, motion, tracks, method=method).points
                times.append((time.perf_counter() - t0) * 1e6)
            return statistics.median(times)
        c, py = rounds(lambda: cxx("estimate", camera_file, rig_path, m_path, t_path, method, a.repeats), python_round)
        over = 100 * (py - c) / c
        verdict = ("met" if over < 10 else "MISSED") if target else "(no target)"
        missed |= target and over >= 10
        rows.append(f"| estimatePoints, {method}, 30 points x 10 frames | {c:.1f} µs | {py:.1f} µs | "
                    f"{py - c:+.1f} µs ({over:+.1f} %) | under 10 % above C++: {verdict} |")
    # DepthProvider: 4 features x 200 periods
    m_path, t_path = scene("update", "--frames", "200", "--points", "4", "--step", "0.005", "--sigma-px", "0.2",
                           "--seed", "5")
    motion, tracks = load(m_path, t_path)
    samples = motion.samples
    features = [tracks[tracks[:, 0] == row[0]][:, 1:].copy() for row in samples]
    reps = max(5, a.repeats // 50)

    def python_updates():
        times = []
        for _ in range(reps):
            provider = yawdepth.DepthProvider(camera, rig)
            t0 = time.perf_counter()
            for row, f in zip(samples, features):
                provider.updateOdometry(row, f)
            times.append((time.perf_counter() - t0) * 1e6 / len(samples))
        return statistics.median(times)
    c, py = rounds(lambda: cxx("update", camera_file, rig_path, m_path, t_path, reps), python_updates)
    verdict = "met" if py - c < 20 else "MISSED"
    missed |= py - c >= 20
    rows.append(f"| DepthProvider.updateOdometry, 4 features (per update, 200 periods) | {c:.1f} µs | {py:.1f} µs | "
                f"{py - c:+.1f} µs | under 20 µs added: {verdict} |")
    print("| Call | C++ | Python | Added by Python | Target |")
    print("|---|---|---|---|---|")
    print("\n".join(rows))
    print(f"\nEach figure: the least of {a.rounds} rounds' medians (estimate: {a.repeats} calls a round; update: "
          f"{reps} runs of {len(samples)} periods a round), the C++ harness and Python taking turns, so that a "
          f"busy machine disturbs both alike; {os.cpu_count()} cores, Python {sys.version.split()[0]}.")
    shutil.rmtree(tmp, ignore_errors=True)
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
