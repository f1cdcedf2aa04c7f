// The drive as a ROS 2 bag (MCAP, zstd chunks), written by the reference libraries of
// tests/data/bags/writers (npm ci --no-audit --no-fund there first): @mcap/core's McapWriter,
// @foxglove/rosmsg2-serialization's CDR MessageWriter from the ROS 2 message definitions below,
// @foxglove/wasm-zstd for the chunks.
//   node write_mcap.mjs PLAN_DIR OUT.mcap [WRITERS_DIR]
//   node write_mcap.mjs --check OUT.mcap [WRITERS_DIR]   (read it back: topics, counts, first values)
// PLAN_DIR is drive_plan.py's output; the topics, frames and times are write_ros1_bag.py's, with the
// ROS 2 types (sensor_msgs/msg/Image, ...). Log times: the stamp plus a transport delay (images 5 ms,
// the others 1 ms), /tf_static at the start with rosbag2's transient_local QoS.
import fs from "node:fs";
import path from "node:path";
import { createRequire } from "node:module";
import { fileURLToPath, pathToFileURL } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
const check = process.argv[2] === "--check";
const args = process.argv.slice(check ? 3 : 2);
const writersDir = path.resolve(args[check ? 1 : 2] ?? path.join(here, "../../tests/data/bags/writers"));
const req = createRequire(path.join(writersDir, "package.json"));
const load = async (name) => import(pathToFileURL(req.resolve(name)).href);
const { McapWriter, McapStreamReader } = await load("@mcap/core");
const { parse } = await load("@foxglove/rosmsg");
const { MessageWriter, MessageReader } = await load("@foxglove/rosmsg2-serialization");
const zstd = await load("@foxglove/wasm-zstd");
await (zstd.isLoaded ?? zstd.default?.isLoaded);
const zcompress = zstd.compress ?? zstd.default.compress;
const zdecompress = zstd.decompress ?? zstd.default.decompress;

// ROS 2 message definitions (the .msg files, dependencies after the type, as ros2msg schemas are).
const dep = (name, text) => `\n================================================================================\nMSG: ${name}\n${text}`;
const HDR = dep("std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id") + dep("builtin_interfaces/Time", "int32 sec\nuint32 nanosec");
const POINT = "float64 x\nfloat64 y\nfloat64 z";
const QUAT = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1";
const POSE_DEPS = dep("geometry_msgs/Pose", "Point position\nQuaternion orientation") + dep("geometry_msgs/Point", POINT) + dep("geometry_msgs/Quaternion", QUAT);
const defs = {
  "sensor_msgs/msg/Image":
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data" + HDR,
  "sensor_msgs/msg/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data" + HDR,
  "sensor_msgs/msg/CameraInfo":
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\nfloat64[9] k\nfloat64[9] r\n" +
    "float64[12] p\nuint32 binning_x\nuint32 binning_y\nRegionOfInterest roi" + HDR +
    dep("sensor_msgs/RegionOfInterest", "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify"),
  "nav_msgs/msg/Odometry":
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist" +
    HDR + dep("geometry_msgs/PoseWithCovariance", "Pose pose\nfloat64[36] covariance") + POSE_DEPS +
    dep("geometry_msgs/TwistWithCovariance", "Twist twist\nfloat64[36] covariance") +
    dep("geometry_msgs/Twist", "Vector3 linear\nVector3 angular") + dep("geometry_msgs/Vector3", POINT),
  "tf2_msgs/msg/TFMessage":
    "geometry_msgs/TransformStamped[] transforms" +
    dep("geometry_msgs/TransformStamped", "std_msgs/Header header\nstring child_frame_id\nTransform transform") + HDR +
    dep("geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation") + dep("geometry_msgs/Vector3", POINT) +
    dep("geometry_msgs/Quaternion", QUAT),
  "sensor_msgs/msg/JointState":
    "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort" + HDR,
};

const QOS = (durability) =>
  `- history: 3\n  depth: 0\n  reliability: 1\n  durability: ${durability}\n  deadline:\n    sec: 2147483647\n    nsec: 4294967295\n` +
  `  lifespan:\n    sec: 2147483647\n    nsec: 4294967295\n  liveliness: 1\n  liveliness_lease_duration:\n` +
  `    sec: 2147483647\n    nsec: 4294967295\n  avoid_ros_namespace_conventions: false\n`;

if (check) {
  // Read it back with @mcap/core's stream reader: every record, chunks decompressed, CDR decoded.
  const file = args[0];
  const reader = new McapStreamReader({ decompressHandlers: { zstd: (data, size) => zdecompress(data, Number(size)) } });
  reader.append(fs.readFileSync(file));
  const schemas = new Map(), channels = new Map(), counts = new Map(), first = new Map();
  let rec, header;
  while ((rec = reader.nextRecord())) {
    if (rec.type === "Header") header = rec;
    if (rec.type === "Schema") schemas.set(rec.id, new MessageReader(parse(new TextDecoder().decode(rec.data), { ros2: true })));
    if (rec.type === "Channel") channels.set(rec.id, rec);
    if (rec.type === "Message") {
      const ch = channels.get(rec.channelId);
      counts.set(ch.topic, (counts.get(ch.topic) ?? 0) + 1);
      if (!first.has(ch.topic)) first.set(ch.topic, schemas.get(ch.schemaId).readMessage(rec.data));
    }
  }
  if (!reader.done()) throw new Error(`${file}: truncated`);
  console.log(`${file}: profile ${header.profile}, ${[...counts.values()].reduce((a, b) => a + b, 0)} messages`);
  for (const [topic, n] of [...counts.entries()].sort()) {
    const m = first.get(topic);
    const st = m.header ?? m.transforms?.[0]?.header;
    console.log(`  ${topic}: ${n} messages, first stamp ${st.stamp.sec}.${String(st.stamp.nanosec).padStart(9, "0")}` +
      (m.encoding ? `, ${m.width}x${m.height} ${m.encoding}, ${m.data.length} bytes` : "") +
      (m.format ? `, ${m.format}, ${m.data.length} bytes` : "") +
      (m.name ? `, ${m.name.join(" ")} = ${m.position.join(" ")}` : "") +
      (m.transforms ? `, ${m.transforms.map((t) => `${t.header.frame_id}->${t.child_frame_id}`).join(" ")}` : "") +
      (m.child_frame_id !== undefined && !m.transforms ? `, ${m.header.frame_id}->${m.child_frame_id}` : ""));
  }
  process.exit(0);
}

const planDir = path.resolve(args[0]);
const outFile = path.resolve(args[1]);
const plan = JSON.parse(fs.readFileSync(path.join(planDir, "plan.json"), "utf8"));
const writers = {};
for (const [type, text] of Object.entries(defs)) writers[type] = new MessageWriter(parse(text, { ros2: true }));

const ns = (st, delay = 0) => BigInt(st[0]) * 1000000000n + BigInt(st[1]) + BigInt(delay);
const time = (st) => ({ sec: st[0], nanosec: st[1] });
const xyz = (v) => ({ x: v[0], y: v[1], z: v[2] });
const xyzw = (q) => ({ x: q[0], y: q[1], z: q[2], w: q[3] });
const diag = (s) => Array.from({ length: 36 }, (_, i) => (i % 7 === 0 ? s : 0));
const messages = []; // {topic, type, log_time, value}
const add = (topic, type, log_time, value) => messages.push({ topic, type, log_time, value });

add("/tf_static", "tf2_msgs/msg/TFMessage", ns(plan.tf_static_stamp), {
  transforms: plan.tf_static.map((s) => ({
    header: { stamp: time(plan.tf_static_stamp), frame_id: s.parent },
    child_frame_id: s.child,
    transform: { translation: xyz(s.t), rotation: xyzw(s.q) },
  })),
});
const cam = plan.camera;
for (const f of plan.frames) {
  const header = { stamp: time(f.stamp), frame_id: "camera_optical_frame" };
  add("/camera/image_raw", "sensor_msgs/msg/Image", ns(f.stamp, 5000000), {
    header, height: cam.height, width: cam.width, encoding: "mono8", is_bigendian: 0, step: cam.width,
    data: new Uint8Array(fs.readFileSync(path.join(planDir, f.gray))),
  });
  add("/camera/image_raw/compressed", "sensor_msgs/msg/CompressedImage", ns(f.stamp, 5000000), {
    header, format: "mono8; png compressed ", data: new Uint8Array(fs.readFileSync(f.png)),
  });
  add("/camera/camera_info", "sensor_msgs/msg/CameraInfo", ns(f.stamp, 1000000), {
    header, height: cam.height, width: cam.width, distortion_model: cam.distortion_model, d: cam.d, k: cam.k, r: cam.r, p: cam.p,
    binning_x: 0, binning_y: 0, roi: { x_offset: 0, y_offset: 0, height: 0, width: 0, do_rectify: false },
  });
}
for (const o of plan.odom) {
  const header = { stamp: time(o.stamp), frame_id: "odom" };
  add("/odom", "nav_msgs/msg/Odometry", ns(o.stamp, 1000000), {
    header, child_frame_id: "base_link",
    pose: { pose: { position: xyz(o.p), orientation: xyzw(o.q) }, covariance: diag(1e-8) },
    twist: { twist: { linear: xyz(o.v), angular: xyz(o.w) }, covariance: diag(1e-6) },
  });
  add("/tf", "tf2_msgs/msg/TFMessage", ns(o.stamp, 1000000), {
    transforms: [{ header, child_frame_id: "base_link", transform: { translation: xyz(o.p), rotation: xyzw(o.q) } }],
  });
}
for (const j of plan.joints)
  add("/joint_states", "sensor_msgs/msg/JointState", ns(j.stamp, 1000000), {
    header: { stamp: time(j.stamp), frame_id: "" }, name: [plan.joint_name], position: [j.position], velocity: [j.velocity], effort: [0],
  });
messages.sort((a, b) => (a.log_time < b.log_time ? -1 : a.log_time > b.log_time ? 1 : 0));

const parts = [];
let size = 0n;
const sink = { position: () => size, write: async (b) => { parts.push(Buffer.from(b)); size += BigInt(b.length); } };
const writer = new McapWriter({
  writable: sink,
  useChunks: true,
  chunkSize: 4 * 1024 * 1024,
  compressChunk: (data) => ({ compression: "zstd", compressedData: zcompress(data, 3) }),
});
await writer.start({ profile: "ros2", library: "yawdepth examples/bag_drive (@mcap/core)" });
const schemas = {}, channels = {};
let seq = 0;
for (const m of messages) {
  if (!(m.type in schemas)) schemas[m.type] = await writer.registerSchema({ name: m.type, encoding: "ros2msg", data: Buffer.from(defs[m.type]) });
  if (!(m.topic in channels))
    channels[m.topic] = await writer.registerChannel({
      schemaId: schemas[m.type], topic: m.topic, messageEncoding: "cdr",
      metadata: new Map([["offered_qos_profiles", QOS(m.topic === "/tf_static" ? 1 : 2)]]),
    });
  await writer.addMessage({ channelId: channels[m.topic], sequence: seq++, logTime: m.log_time, publishTime: m.log_time, data: writers[m.type].writeMessage(m.value) });
}
await writer.end();
fs.writeFileSync(outFile, Buffer.concat(parts));
console.log(`write_mcap: ${outFile}: ${messages.length} messages, ${(Number(size) / 1e6).toFixed(1)} MB`);
