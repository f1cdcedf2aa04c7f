#!/usr/bin/env python3
"""A large rosbag2 SQLite bag (.db3) for bench_import_bag.sh: the messages write_large_mcap.mjs wrote
into its MCAP (--messages FILE: the CDR payloads of ROS 2's reference serializer), put into the schema
rosbag2_storage_default_plugins creates (version 4, as Jazzy writes it; rows in time order, one
transaction per 256 rows, as rosbag2's sqlite3 storage batches them), so the three formats carry the
same messages.
  write_large_db3.py MESSAGES OUT.db3"""
import sqlite3
import struct
import sys

src, out = sys.argv[1], sys.argv[2]
db = sqlite3.connect(out)
db.executescript("""
    PRAGMA journal_mode = MEMORY;
    PRAGMA synchronous = OFF;
    CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
    CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);
    CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                        serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL,
                        type_description_hash TEXT NOT NULL);
    CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL, encoding TEXT NOT NULL,
                                     encoded_message_definition TEXT NOT NULL, type_description_hash TEXT NOT NULL);
    CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL,
                          data BLOB NOT NULL);
    CREATE INDEX timestamp_idx ON messages (timestamp ASC);
    INSERT INTO schema VALUES (4, 'jazzy');
""")
topics = {}
batch = []
with open(src, "rb") as f:
    while True:
        head = f.read(2)
        if not head:
            break
        topic = f.read(struct.unpack("<H", head)[0]).decode()
        type_ = f.read(struct.unpack("<H", f.read(2))[0]).decode()
        ns, size = struct.unpack("<QI", f.read(12))
        data = f.read(size)
        if topic not in topics:
            topics[topic] = len(topics) + 1
            db.execute("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '', ?)",
                       (topics[topic], topic, type_, "RIHS01_" + "0" * 64))
        batch.append((topics[topic], ns, data))
        if len(batch) == 256:
            db.executemany("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)", batch)
            db.commit()
            batch = []
db.executemany("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)", batch)
db.commit()
db.close()
