// Writes the ROS 2 bags of yawdepth's bag reader tests with the reference libraries: MCAP through
// @mcap/core's McapWriter (chunks uncompressed, zstd through @foxglove/wasm-zstd, lz4 frames through
// lz4js; and a file without chunks or summary), CDR through @foxglove/rosmsg2-serialization's
// MessageWriter from the ROS 2 message definitions below (parsed by @foxglove/rosmsg). Also the CDR
// payloads for make_db3.py, and ros2_expected.json: every value written, times as decimal strings.
//   node make_ros2_bags.mjs [--out DIR] [--seed N | --random] [--fuzz-seeds DIR]
// The checked-in bags are seed 1 (the default) into ../ (tests/data/bags/). --fuzz-seeds also writes
// the fuzzers' seed corpora: DIR/mcap (small MCAP files without their magic), DIR/cdr (a type byte,
// fuzz_cdr.cpp's order, then a payload).
import { McapWriter } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
import * as zstd from "@foxglove/wasm-zstd";
import lz4 from "lz4js";
import fs from "node:fs";
import path from "node:path";
import zlib from "node:zlib";
import { fileURLToPath } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
let out = path.resolve(here, "..");
let seed = 1;
let fuzzSeeds;
for (let i = 2; i < process.argv.length; ++i) {
  const a = process.argv[i];
  if (a === "--out") out = path.resolve(process.argv[++i]);
  else if (a === "--seed") seed = Number(process.argv[++i]);
  else if (a === "--fuzz-seeds") fuzzSeeds = path.resolve(process.argv[++i]);
  else if (a === "--random") seed = Math.floor(Math.random() * 2 ** 31) + 1;
  else throw new Error(`unknown argument ${a}`);
}
fs.mkdirSync(out, { recursive: true });

// mulberry32: reproducible values for a seed.
let state = seed >>> 0;
function rand() {
  state = (state + 0x6d2b79f5) >>> 0;
  let t = state;
  t = Math.imul(t ^ (t >>> 15), t | 1);
  t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
  return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
}
const uniform = (a, b) => a + (b - a) * rand();
const int = (n) => Math.floor(rand() * n);

// ROS 2 message definitions (the .msg files, dependencies after the type, as ros2msg schemas are).
const TIME = "int32 sec\nuint32 nanosec";
const HEADER = "builtin_interfaces/Time stamp\nstring frame_id";
const dep = (name, text) => `\n================================================================================\nMSG: ${name}\n${text}`;
const HDR = dep("std_msgs/Header", HEADER) + dep("builtin_interfaces/Time", TIME);
const POINT = "float64 x\nfloat64 y\nfloat64 z";
const QUAT = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1";
const POSE = "Point position\nQuaternion orientation";
const POSE_DEPS = dep("geometry_msgs/Pose", POSE) + dep("geometry_msgs/Point", POINT) + dep("geometry_msgs/Quaternion", QUAT);
const PWC = "Pose pose\nfloat64[36] covariance";
const TWIST_DEPS =
  dep("geometry_msgs/TwistWithCovariance", "Twist twist\nfloat64[36] covariance") +
  dep("geometry_msgs/Twist", "Vector3 linear\nVector3 angular") +
  dep("geometry_msgs/Vector3", POINT);
const TRANSFORM_STAMPED = "std_msgs/Header header\nstring child_frame_id\nTransform transform";
const TRANSFORM_DEPS =
  dep("geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation") +
  dep("geometry_msgs/Vector3", POINT) +
  dep("geometry_msgs/Quaternion", QUAT);
const defs = {
  "sensor_msgs/msg/Image":
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data" + HDR,
  "sensor_msgs/msg/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data" + HDR,
  "sensor_msgs/msg/CameraInfo":
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\nfloat64[9] k\nfloat64[9] r\n" +
    "float64[12] p\nuint32 binning_x\nuint32 binning_y\nRegionOfInterest roi" + HDR +
    dep("sensor_msgs/RegionOfInterest", "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify"),
  "geometry_msgs/msg/PoseStamped": "std_msgs/Header header\nPose pose" + HDR + POSE_DEPS,
  "geometry_msgs/msg/PoseWithCovarianceStamped":
    "std_msgs/Header header\nPoseWithCovariance pose" + HDR + dep("geometry_msgs/PoseWithCovariance", PWC) + POSE_DEPS,
  "nav_msgs/msg/Odometry":
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist" +
    HDR + dep("geometry_msgs/PoseWithCovariance", PWC) + POSE_DEPS + TWIST_DEPS,
  "tf2_msgs/msg/TFMessage":
    "geometry_msgs/TransformStamped[] transforms" + dep("geometry_msgs/TransformStamped", TRANSFORM_STAMPED) + HDR + TRANSFORM_DEPS,
  "sensor_msgs/msg/JointState":
    "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort" + HDR,
};
const writers = {};
for (const [type, text] of Object.entries(defs)) writers[type] = new MessageWriter(parse(text, { ros2: true }));

// A real PNG (3x2 RGB), for the CompressedImage.
function crc32(buf) {
  let c = ~0;
  for (const b of buf) {
    c ^= b;
    for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  }
  return ~c >>> 0;
}
function png(w, h, rgb) {
  const chunk = (type, data) => {
    const len = Buffer.alloc(4);
    len.writeUInt32BE(data.length);
    const td = Buffer.concat([Buffer.from(type, "ascii"), data]);
    const crc = Buffer.alloc(4);
    crc.writeUInt32BE(crc32(td));
    return Buffer.concat([len, td, crc]);
  };
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(w, 0);
  ihdr.writeUInt32BE(h, 4);
  ihdr[8] = 8; // bit depth
  ihdr[9] = 2; // RGB
  const rows = [];
  for (let y = 0; y < h; ++y) rows.push(Buffer.from([0]), Buffer.from(rgb.slice(y * w * 3, (y + 1) * w * 3)));
  return Buffer.concat([
    Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]),
    chunk("IHDR", ihdr),
    chunk("IDAT", zlib.deflateSync(Buffer.concat(rows))),
    chunk("IEND", Buffer.alloc(0)),
  ]);
}

// The messages, in log-time order.
const t0 = 1700000000n * 1000000000n + BigInt(int(1e9));
const messages = []; // {topic, type, log_time (bigint), value}
let tick = 0n;
const stamp = () => ({ sec: 1700000000 + int(100), nanosec: int(1000000000) });
const header = (frame) => ({ stamp: stamp(), frame_id: frame });
const quat = () => {
  const q = [uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)];
  return { x: q[0], y: q[1], z: q[2], w: q[3] };
};
const vec = () => ({ x: uniform(-5, 5), y: uniform(-5, 5), z: uniform(-5, 5) });
const doubles = (n) => Array.from({ length: n }, () => uniform(-10, 10));
const add = (topic, type, value) => {
  tick += BigInt(1000000 + int(30000000));
  messages.push({ topic, type, log_time: t0 + tick, value });
};
const image = (encoding, bpp) => {
  const w = 8, h = 6;
  return {
    header: header("camera_optical"),
    height: h,
    width: w,
    encoding,
    is_bigendian: 0,
    step: w * bpp,
    data: Uint8Array.from({ length: w * h * bpp }, () => int(256)),
  };
};
const tf = (n, parent) => ({
  transforms: Array.from({ length: n }, (_, i) => ({
    header: header(i === 0 ? parent : `link_${i}`),
    child_frame_id: `link_${i + 1}`,
    transform: { translation: vec(), rotation: quat() },
  })),
});

add("/tf_static", "tf2_msgs/msg/TFMessage", tf(3, "base_link"));
for (let k = 0; k < 3; ++k) {
  add("/camera/camera_info", "sensor_msgs/msg/CameraInfo", {
    header: header("camera_optical"),
    height: 6,
    width: 8,
    distortion_model: k === 2 ? "rational_polynomial" : "plumb_bob",
    d: doubles(k === 2 ? 8 : 5),
    k: doubles(9),
    r: doubles(9),
    p: doubles(12),
    binning_x: int(3),
    binning_y: int(3),
    roi: { x_offset: int(8), y_offset: int(6), height: int(6), width: int(8), do_rectify: rand() < 0.5 },
  });
  add("/camera/mono8", "sensor_msgs/msg/Image", image("mono8", 1));
  add("/camera/rgb8", "sensor_msgs/msg/Image", image("rgb8", 3));
  add("/camera/bgr8", "sensor_msgs/msg/Image", image("bgr8", 3));
  add("/camera/mono16", "sensor_msgs/msg/Image", image("mono16", 2));
  add("/camera/compressed", "sensor_msgs/msg/CompressedImage", {
    header: header("camera_optical"),
    format: "png",
    data: Uint8Array.from(png(3, 2, Array.from({ length: 18 }, () => int(256)))),
  });
  add("/odom", "nav_msgs/msg/Odometry", {
    header: header("odom"),
    child_frame_id: "base_link",
    pose: { pose: { position: vec(), orientation: quat() }, covariance: doubles(36) },
    twist: { twist: { linear: vec(), angular: vec() }, covariance: doubles(36) },
  });
  add("/pose", "geometry_msgs/msg/PoseStamped", { header: header("map"), pose: { position: vec(), orientation: quat() } });
  add("/pose_cov", "geometry_msgs/msg/PoseWithCovarianceStamped", {
    header: header("map"),
    pose: { pose: { position: vec(), orientation: quat() }, covariance: doubles(36) },
  });
  add("/tf", "tf2_msgs/msg/TFMessage", tf(2 + k, "odom"));
  add("/joint_states", "sensor_msgs/msg/JointState", {
    header: header(""),
    name: ["joint_a", "joint_b", "wrist"],
    position: doubles(3),
    velocity: doubles(3),
    effort: k === 1 ? [] : doubles(3),
  });
}
for (const m of messages) m.cdr = writers[m.type].writeMessage(m.value);

// MCAP files.
class Sink {
  constructor() {
    this.parts = [];
    this.size = 0n;
  }
  position() {
    return this.size;
  }
  async write(b) {
    this.parts.push(Buffer.from(b));
    this.size += BigInt(b.length);
  }
}
await zstd.isLoaded;
const compressors = {
  none: undefined,
  zstd: (data) => ({ compression: "zstd", compressedData: zstd.compress(data, 3) }),
  lz4: (data) => ({ compression: "lz4", compressedData: Uint8Array.from(lz4.compress(data)) }),
};
let schemaText = true; // the fuzz seeds leave the schemas' text out (the reader does not read it)
async function writeMcap(file, list, options) {
  const sink = new Sink();
  const writer = new McapWriter({ writable: sink, ...options });
  await writer.start({ profile: "ros2", library: "yawdepth tests (@mcap/core)" });
  const schemas = {}, channels = {};
  for (const m of list) {
    if (!(m.type in schemas))
      schemas[m.type] = await writer.registerSchema({ name: m.type, encoding: "ros2msg", data: schemaText ? Buffer.from(defs[m.type]) : new Uint8Array() });
    if (!(m.topic in channels))
      channels[m.topic] = await writer.registerChannel({
        schemaId: schemas[m.type],
        topic: m.topic,
        messageEncoding: "cdr",
        metadata: new Map([["offered_qos_profiles", ""]]),
      });
  }
  let seq = 0;
  for (const [i, m] of list.entries()) {
    await writer.addMessage({ channelId: channels[m.topic], sequence: seq++, logTime: m.log_time, publishTime: m.log_time, data: m.cdr });
    if (i === 3 && schemaText) {
      // Records a bag reader skips: an attachment and metadata, between messages (and chunks).
      await writer.addAttachment({
        name: "camera.yaml",
        logTime: m.log_time,
        createTime: m.log_time,
        mediaType: "application/yaml",
        data: Buffer.from("image_width: 8\nimage_height: 6\n"),
      });
      await writer.addMetadata({ name: "robot", metadata: new Map([["model", "yawbot"], ["serial", "0001"]]) });
    }
  }
  await writer.end();
  fs.writeFileSync(path.join(out, file), Buffer.concat(sink.parts));
}
const chunked = (compression) => ({ useChunks: true, chunkSize: 4096, compressChunk: compressors[compression] });
await writeMcap("ros2_plain.mcap", messages, { ...chunked("none") });
await writeMcap("ros2_zstd.mcap", messages, chunked("zstd"));
await writeMcap("ros2_lz4.mcap", messages, chunked("lz4"));
await writeMcap("ros2_unchunked.mcap", messages, {
  useChunks: false,
  useStatistics: false,
  useSummaryOffsets: false,
  repeatSchemas: false,
  repeatChannels: false,
  useAttachmentIndex: false,
  useMetadataIndex: false,
  useMessageIndex: false,
  useChunkIndex: false,
});
// A bag folder of two MCAP files (rosbag2's split) with its metadata.yaml.
const split = path.join(out, "ros2_split");
fs.mkdirSync(split, { recursive: true });
const half = Math.floor(messages.length / 2);
await writeMcap("ros2_split/ros2_split_0.mcap", messages.slice(0, half), chunked("zstd"));
await writeMcap("ros2_split/ros2_split_1.mcap", messages.slice(half), chunked("lz4"));
const topicsOf = (list) => [...new Map(list.map((m) => [m.topic, m.type])).entries()];
const count = (list, topic) => list.filter((m) => m.topic === topic).length;
fs.writeFileSync(
  path.join(split, "metadata.yaml"),
  [
    "rosbag2_bagfile_information:",
    "  version: 5",
    "  storage_identifier: mcap",
    "  relative_file_paths:",
    "    - ros2_split_0.mcap",
    "    - ros2_split_1.mcap",
    "  duration:",
    `    nanoseconds: ${messages[messages.length - 1].log_time - messages[0].log_time}`,
    "  starting_time:",
    `    nanoseconds_since_epoch: ${messages[0].log_time}`,
    `  message_count: ${messages.length}`,
    "  topics_with_message_count:",
    ...topicsOf(messages).flatMap(([topic, type]) => [
      "    - topic_metadata:",
      `        name: ${topic}`,
      `        type: ${type}`,
      "        serialization_format: cdr",
      '        offered_qos_profiles: ""',
      `      message_count: ${count(messages, topic)}`,
    ]),
    '  compression_format: ""',
    '  compression_mode: ""',
    "",
  ].join("\n"),
);

// The CDR payloads for make_db3.py, and the values written.
const json = (v) =>
  JSON.stringify(v, (k, x) => (typeof x === "bigint" ? x.toString() : x instanceof Uint8Array ? Array.from(x) : x));
fs.writeFileSync(
  path.join(out, "ros2_payloads.json"),
  json({
    topics: topicsOf(messages).map(([name, type]) => ({ name, type })),
    messages: messages.map((m) => ({ topic: m.topic, log_time: m.log_time, cdr: Buffer.from(m.cdr).toString("base64") })),
  }) + "\n",
);
fs.writeFileSync(
  path.join(out, "ros2_expected.json"),
  json({ seed, messages: messages.map((m) => ({ topic: m.topic, type: m.type, log_time: m.log_time, value: m.value })) }) + "\n",
);

if (fuzzSeeds) {
  const order = [
    "sensor_msgs/msg/Image",
    "sensor_msgs/msg/CompressedImage",
    "sensor_msgs/msg/CameraInfo",
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/PoseWithCovarianceStamped",
    "nav_msgs/msg/Odometry",
    "tf2_msgs/msg/TFMessage",
    "sensor_msgs/msg/JointState",
  ];
  fs.mkdirSync(path.join(fuzzSeeds, "cdr"), { recursive: true });
  fs.mkdirSync(path.join(fuzzSeeds, "mcap"), { recursive: true });
  const seen = new Set();
  const small = [];
  for (const m of messages) {
    if (seen.has(m.topic) || m.topic === "/camera/rgb8" || m.topic === "/camera/bgr8" || m.topic === "/camera/mono16") continue;
    seen.add(m.topic);
    small.push(m);
    fs.writeFileSync(
      path.join(fuzzSeeds, "cdr", m.topic.replace(/\//g, "_").slice(1)),
      Buffer.concat([Buffer.from([order.indexOf(m.type)]), Buffer.from(m.cdr)]),
    );
  }
  const saved = out;
  out = path.join(fuzzSeeds, "mcap");
  schemaText = false;
  const tiny = (compression) => ({ useChunks: true, chunkSize: 1024, compressChunk: compressors[compression] });
  await writeMcap("plain", small, tiny("none"));
  await writeMcap("zstd", small, tiny("zstd"));
  await writeMcap("lz4", small, tiny("lz4"));
  await writeMcap("unchunked", small, { useChunks: false, useStatistics: false, useSummaryOffsets: false, repeatSchemas: false, repeatChannels: false, useAttachmentIndex: false, useMetadataIndex: false, useMessageIndex: false, useChunkIndex: false });
  for (const f of ["plain", "zstd", "lz4", "unchunked"]) {
    const b = fs.readFileSync(path.join(out, f));
    fs.writeFileSync(path.join(out, f), b.subarray(8)); // fuzz_mcap adds the magic
  }
  out = saved;
}
