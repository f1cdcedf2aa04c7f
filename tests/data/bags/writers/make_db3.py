#!/usr/bin/env python3
"""rosbag2's SQLite bags (.db3) of the CDR payloads make_ros2_bags.mjs wrote (ros2_payloads.json),
with rosbag2_storage_default_plugins' schema:
  DIR/ros2.db3                 schema version 4 (Jazzy: topics.type_description_hash, message_definitions)
  DIR/ros2_db3/metadata.yaml   a bag folder, its ros2_db3_0.db3 of schema version 3 (Humble)
  DIR/ros2_zstd_message/       a bag folder of rosbag2's MESSAGE compression: each message's CDR bytes
                               one zstd frame (by the zstd command, the format's reference implementation;
                               every other frame without its content size, as a streaming writer makes them)
  DIR/ros2_zstd_file/          rosbag2's FILE compression: ros2_zstd_file_0.db3.zstd, the whole database
                               compressed by the zstd command
  DIR/ros2_zstd_mcap/          FILE compression of DIR/ros2_plain.mcap (@mcap/core's, make_ros2_bags.mjs)
Rows are inserted out of timestamp order: a reader must sort by timestamp.
  make_db3.py [DIR]   (default: tests/data/bags/)
  make_db3.py DIR --fuzz-seed FILE   also a small .db3 (512-byte pages, a few messages) for fuzz_db3, and
                                     beside it the same compressed by rosbag2's two modes (_zstd_message.db3,
                                     _zstd_file.db3.zstd)"""
import base64
import json
import os
import random
import sqlite3
import subprocess
import sys
import tempfile

here = os.path.dirname(os.path.abspath(__file__))
out = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else os.path.dirname(here)
fuzz_seed = sys.argv[3] if len(sys.argv) > 3 and sys.argv[2] == "--fuzz-seed" else None
with open(os.path.join(out, "ros2_payloads.json")) as f:
    payloads = json.load(f)
topics = payloads["topics"]
messages = payloads["messages"]


def zstd_bytes(data, known_size):
    """data compressed by the zstd command: from a file (the frame declares its size) or a pipe (it does not)."""
    if not known_size:
        return subprocess.run(["zstd", "-q", "-c"], input=data, capture_output=True, check=True).stdout
    with tempfile.NamedTemporaryFile() as f:
        f.write(data)
        f.flush()
        return subprocess.run(["zstd", "-q", "-c", f.name], capture_output=True, check=True).stdout


def write(path, version, small=False, compress_messages=False):
    if os.path.exists(path):
        os.remove(path)
    db = sqlite3.connect(path)
    if small:
        db.execute("PRAGMA page_size = 512")
    hash_column = ", type_description_hash TEXT NOT NULL" if version >= 4 else ""
    db.executescript(f"""
        CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
        CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);
        CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                            serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL{hash_column});
        CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL,
                              data BLOB NOT NULL);
        CREATE INDEX timestamp_idx ON messages (timestamp ASC);
    """)
    if version >= 4:
        db.execute("CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL, "
                   "encoding TEXT NOT NULL, encoded_message_definition TEXT NOT NULL, "
                   "type_description_hash TEXT NOT NULL)")
    db.execute("INSERT INTO schema VALUES (?, ?)", (version, "jazzy" if version >= 4 else "humble"))
    ids = {}
    for i, t in enumerate(topics):
        ids[t["name"]] = i + 3  # ids need not start at 1
        row = (ids[t["name"]], t["name"], t["type"], "cdr", "")
        db.execute(f"INSERT INTO topics VALUES (?, ?, ?, ?, ?{', ?' if version >= 4 else ''})",
                   row + (("RIHS01_" + "0" * 64,) if version >= 4 else ()))
    rows = [(ids[m["topic"]], int(m["log_time"]), base64.b64decode(m["cdr"])) for m in messages]
    if small:
        rows = [r for r in rows if len(r[2]) < 200][:8]
    if compress_messages:
        rows = [(t, ts, zstd_bytes(d, i % 2 == 0)) for i, (t, ts, d) in enumerate(rows)]
    random.Random(7).shuffle(rows)
    db.executemany("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)", rows)
    db.commit()
    db.execute("VACUUM")
    db.close()


write(os.path.join(out, "ros2.db3"), 4)
folder = os.path.join(out, "ros2_db3")
os.makedirs(folder, exist_ok=True)
write(os.path.join(folder, "ros2_db3_0.db3"), 3)
def metadata(folder, files, storage="sqlite3", mode=""):
    """rosbag2's metadata.yaml (version 5) for the messages in `files`; mode FILE or MESSAGE: zstd."""
    counts = {t["name"]: sum(1 for m in messages if m["topic"] == t["name"]) for t in topics}
    times = [int(m["log_time"]) for m in messages]
    lines = ["rosbag2_bagfile_information:", "  version: 5", f"  storage_identifier: {storage}",
             "  duration:", f"    nanoseconds: {max(times) - min(times)}",
             "  starting_time:", f"    nanoseconds_since_epoch: {min(times)}",
             f"  message_count: {len(messages)}", "  topics_with_message_count:"]
    for t in topics:
        lines += ["    - topic_metadata:", f"        name: {t['name']}", f"        type: {t['type']}",
                  "        serialization_format: cdr", '        offered_qos_profiles: ""',
                  f"      message_count: {counts[t['name']]}"]
    lines += [f'  compression_format: "{"zstd" if mode else ""}"', f'  compression_mode: "{mode}"',
              "  relative_file_paths:"] + [f"    - {f}" for f in files] + [""]
    with open(os.path.join(folder, "metadata.yaml"), "w") as f:
        f.write("\n".join(lines))


metadata(folder, ["ros2_db3_0.db3"])


def compressed_folder(name, files, storage, mode):
    folder = os.path.join(out, name)
    os.makedirs(folder, exist_ok=True)
    for f in os.listdir(folder):
        os.remove(os.path.join(folder, f))
    metadata(folder, files, storage, mode)
    return folder


folder = compressed_folder("ros2_zstd_message", ["ros2_zstd_message_0.db3"], "sqlite3", "MESSAGE")
write(os.path.join(folder, "ros2_zstd_message_0.db3"), 3, compress_messages=True)
folder = compressed_folder("ros2_zstd_file", ["ros2_zstd_file_0.db3.zstd"], "sqlite3", "FILE")
write(os.path.join(folder, "ros2_zstd_file_0.db3"), 3)
subprocess.run(["zstd", "-q", "--rm", os.path.join(folder, "ros2_zstd_file_0.db3"), "-o",
                os.path.join(folder, "ros2_zstd_file_0.db3.zstd")], check=True)
folder = compressed_folder("ros2_zstd_mcap", ["ros2_zstd_mcap_0.mcap.zstd"], "mcap", "FILE")
subprocess.run(["zstd", "-q", "-c", os.path.join(out, "ros2_plain.mcap"), "-o",
                os.path.join(folder, "ros2_zstd_mcap_0.mcap.zstd")], check=True)

# Two refused databases: an SQLite file that is not a rosbag2 bag, and a topic not in CDR.
broken = os.path.join(out, "broken")
os.makedirs(broken, exist_ok=True)
for name in ("not_rosbag2.db3", "json_topic.db3"):
    if os.path.exists(os.path.join(broken, name)):
        os.remove(os.path.join(broken, name))
db = sqlite3.connect(os.path.join(broken, "not_rosbag2.db3"))
db.executescript("CREATE TABLE readings(id INTEGER PRIMARY KEY, value REAL); INSERT INTO readings VALUES (1, 2.5);")
db.commit()
db.close()
db = sqlite3.connect(os.path.join(broken, "json_topic.db3"))
db.executescript("""
    CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                        serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
    CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL,
                          data BLOB NOT NULL);
    INSERT INTO topics VALUES (1, '/status', 'std_msgs/msg/String', 'json', '');
    INSERT INTO messages VALUES (1, 1, 1700000000000000000, '{"data": "ok"}');
""")
db.commit()
db.close()

if fuzz_seed:
    write(fuzz_seed, 3, small=True)
    # rosbag2's compression for the fuzzer: the small database's messages (MESSAGE) and the file (FILE).
    stem = fuzz_seed[:-4] if fuzz_seed.endswith(".db3") else fuzz_seed
    write(stem + "_zstd_message.db3", 3, small=True, compress_messages=True)
    subprocess.run(["zstd", "-q", "-f", "-19", fuzz_seed, "-o", stem + "_zstd_file.db3.zstd"], check=True)
