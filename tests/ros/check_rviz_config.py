#!/usr/bin/env python3
"""The node's RViz config (modules/ros1/rviz/yawdepth.rviz) as RViz reads it: valid YAML (RViz refuses
a file that is not, and then starts empty), every display of a known RViz class, its topics the node's
outputs, the fixed frame set. Exits 1 naming what is wrong.

    check_rviz_config.py RVIZ_FILE
"""
import sys

import yaml

NODE_TOPICS = {"/yawdepth_node/points", "/yawdepth_node/points_camera", "/yawdepth_node/markers",
               "/yawdepth_node/tracks"}   # docs/ros.md, "Topics"
TOPIC_KEYS = ("Topic", "Marker Topic", "Image Topic")
CLASSES = {"rviz/Grid", "rviz/TF", "rviz/PointCloud2", "rviz/MarkerArray", "rviz/Image"}


def main():
    path = sys.argv[1]
    try:
        with open(path) as f:
            config = yaml.safe_load(f)
    except (OSError, yaml.YAMLError) as e:
        print(f"{path}: not a readable YAML file: {e}".replace("\n", " "))
        return 1
    problems = []
    manager = config.get("Visualization Manager", {})
    if not manager.get("Global Options", {}).get("Fixed Frame"):
        problems.append("no Global Options / Fixed Frame")
    displays = manager.get("Displays", [])
    topics = set()
    for d in displays:
        if d.get("Class") not in CLASSES:
            problems.append(f"display {d.get('Name')!r}: class {d.get('Class')!r}")
        for k in TOPIC_KEYS:
            if k in d:
                topics.add(d[k])
                if d[k] not in NODE_TOPICS:
                    problems.append(f"display {d.get('Name')!r}: topic {d[k]} is not one of the node's")
    for wanted in ("/yawdepth_node/points", "/yawdepth_node/markers", "/yawdepth_node/tracks"):
        if wanted not in topics:
            problems.append(f"no display of {wanted}")
    for p in problems:
        print(f"{path}: {p}")
    if not problems:
        print(f"{path}: {len(displays)} displays, topics {sorted(topics)}: ok")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
