#!/usr/bin/python3
"""Measure a folder of images: detect a pattern in each image of a motion log, build tracks, estimate
the points (what `yawdepth measure --pattern` does, step by step in Python).

    /usr/bin/python3 examples/python/measure_folder.py CAMERA RIG FOLDER/motion.csv PATTERN OUT.csv [METHOD]

motion.csv names each frame's image (`image` column, relative to its folder), as `yawdepth simulate
--pattern` writes it; PATTERN as --pattern, e.g. chessboard:7x5:0.02.
"""
import sys

import yawdepth


def main(camera_path, rig_path, motion_path, pattern, out, method="exact"):
    camera = yawdepth.loadCameraFile(camera_path)
    rig_file = yawdepth.readRigFile(rig_path)
    motion = yawdepth.loadMotion(motion_path, rig_file)
    yawdepth.checkMotionSteps(motion, motion_path)
    yawdepth.applyRigFile(rig_file, motion)

    detector = yawdepth.PatternDetector(pattern)
    detector.setCamera(camera)
    detections = []
    for row, image_path in zip(motion.samples, motion.images):
        image = yawdepth.readGrayImage(image_path, camera)  # (rows, cols) uint8
        d = detector.detect(image, int(row[0]))
        if not d.found:
            print(f"frame {int(row[0])}: {d.reason}", file=sys.stderr)
        detections.append(d)
    tracks = yawdepth.PatternDetector.toTracks(detections)  # (M, 4) [frame, id, u, v]

    result = yawdepth.estimatePoints(camera, rig_file.rig(), motion, tracks, method=method)
    for w in result.warnings:
        print(f"warning: {w}", file=sys.stderr)
    yawdepth.writePointsCsv(out, result)  # the points CSV, as `yawdepth measure --out`
    ok = (result.points["status"] == "ok").sum()
    print(f"{len(tracks)} observations of {len(result.points)} features in {len(motion)} images: {ok} points ok; wrote {out}")


if __name__ == "__main__":
    if len(sys.argv) not in (6, 7):
        sys.exit(__doc__)
    main(*sys.argv[1:])
