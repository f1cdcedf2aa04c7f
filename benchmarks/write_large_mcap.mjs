// A large ROS 2 bag (MCAP, uncompressed chunks, as `ros2 bag record -s mcap` writes by default) for
// bench_import_bag.sh, by the reference libraries of tests/data/bags/writers (@mcap/core's McapWriter,
// @foxglove/rosmsg2-serialization's CDR): the topics of write_large_bag.py with the ROS 2 types.
//   node write_large_mcap.mjs OUT.mcap SIZE_MB PHOTO.raw WIDTH HEIGHT [WRITERS_DIR] [--messages FILE]
// --messages FILE: every message also written to FILE as it went into the MCAP (topic, type, log time,
// CDR payload), for write_large_db3.py, which puts the same messages into rosbag2's SQLite bag.
// PHOTO.raw: 8-bit gray pixels, row by row (write_large_bag.py --raw writes ViSP's Solvay photo so).
import fs from "node:fs";
import path from "node:path";
import { createRequire } from "node:module";
import { fileURLToPath, pathToFileURL } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
const [out, sizeMb, photoPath, pw, ph] = process.argv.slice(2, 7);
const rest = process.argv.slice(7);
const messagesAt = rest.indexOf("--messages");
const messagesPath = messagesAt >= 0 ? rest[messagesAt + 1] : undefined;
if (messagesAt >= 0) rest.splice(messagesAt, 2);
const writersDir = path.resolve(rest[0] ?? path.join(here, "../tests/data/bags/writers"));
const req = createRequire(path.join(writersDir, "package.json"));
const load = async (name) => import(pathToFileURL(req.resolve(name)).href);
const { McapWriter } = await load("@mcap/core");
const { parse } = await load("@foxglove/rosmsg");
const { MessageWriter } = await load("@foxglove/rosmsg2-serialization");

const sep = "\n================================================================================\nMSG: ";
const HDR = `${sep}std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id${sep}builtin_interfaces/Time\nint32 sec\nuint32 nanosec`;
const V3 = "float64 x\nfloat64 y\nfloat64 z";
const Q = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1";
const defs = {
  "sensor_msgs/msg/Image": "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data" + HDR,
  "sensor_msgs/msg/CameraInfo":
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\n" +
    `uint32 binning_x\nuint32 binning_y\nRegionOfInterest roi${HDR}${sep}sensor_msgs/RegionOfInterest\nuint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify`,
  "nav_msgs/msg/Odometry":
    `std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist${HDR}` +
    `${sep}geometry_msgs/PoseWithCovariance\nPose pose\nfloat64[36] covariance${sep}geometry_msgs/Pose\nPoint position\nQuaternion orientation` +
    `${sep}geometry_msgs/Point\n${V3}${sep}geometry_msgs/Quaternion\n${Q}${sep}geometry_msgs/TwistWithCovariance\nTwist twist\nfloat64[36] covariance` +
    `${sep}geometry_msgs/Twist\nVector3 linear\nVector3 angular${sep}geometry_msgs/Vector3\n${V3}`,
  "tf2_msgs/msg/TFMessage":
    `geometry_msgs/TransformStamped[] transforms${sep}geometry_msgs/TransformStamped\nstd_msgs/Header header\nstring child_frame_id\nTransform transform${HDR}` +
    `${sep}geometry_msgs/Transform\nVector3 translation\nQuaternion rotation${sep}geometry_msgs/Vector3\n${V3}${sep}geometry_msgs/Quaternion\n${Q}`,
};
const writers = Object.fromEntries(Object.entries(defs).map(([k, v]) => [k, new MessageWriter(parse(v, { ros2: true }))]));

const photo = fs.readFileSync(photoPath), PW = Number(pw), PH = Number(ph), W = 640, H = 480;
const T0 = 1700000000n * 1000000000n;
const stamp = (ns) => ({ sec: Number(ns / 1000000000n), nanosec: Number(ns % 1000000000n) });
const frames = Math.floor((Number(sizeMb) * 1e6) / (W * H + 600));

const fd = fs.openSync(out, "w");
let size = 0n;
const sink = { position: () => size, write: async (b) => { fs.writeSync(fd, b); size += BigInt(b.length); } };
const writer = new McapWriter({ writable: sink, useChunks: true, chunkSize: 4 * 1024 * 1024 });
await writer.start({ profile: "ros2", library: "yawdepth benchmarks/write_large_mcap.mjs (@mcap/core)" });
const channels = {};
for (const [topic, type] of [["/tf_static", "tf2_msgs/msg/TFMessage"], ["/odom", "nav_msgs/msg/Odometry"],
                             ["/camera/image_raw", "sensor_msgs/msg/Image"], ["/camera/camera_info", "sensor_msgs/msg/CameraInfo"]]) {
  const schemaId = await writer.registerSchema({ name: type, encoding: "ros2msg", data: Buffer.from(defs[type]) });
  channels[topic] = { id: await writer.registerChannel({ schemaId, topic, messageEncoding: "cdr", metadata: new Map() }), type };
}
// --messages' records: u16 topic length, topic, u16 type length, type, u64 log time (ns), u32 size, CDR bytes (little endian).
const messagesFd = messagesPath ? fs.openSync(messagesPath, "w") : undefined;
const record = (topic, type, ns, data) => {
  const t = Buffer.from(topic), y = Buffer.from(type), head = Buffer.alloc(2 + t.length + 2 + y.length + 12);
  let o = head.writeUInt16LE(t.length, 0);
  o += t.copy(head, o);
  o = head.writeUInt16LE(y.length, o);
  o += y.copy(head, o);
  o = head.writeBigUInt64LE(ns, o);
  head.writeUInt32LE(data.length, o);
  fs.writeSync(messagesFd, head);
  fs.writeSync(messagesFd, data);
};
let seq = 0;
const add = async (topic, ns, value) => {
  const data = writers[channels[topic].type].writeMessage(value);
  if (messagesFd !== undefined) record(topic, channels[topic].type, ns, data);
  await writer.addMessage({ channelId: channels[topic].id, sequence: seq++, logTime: ns, publishTime: ns, data });
};
const zeros = (n) => new Array(n).fill(0);
await add("/tf_static", T0, { transforms: [{ header: { stamp: stamp(T0), frame_id: "base_link" }, child_frame_id: "camera_optical_frame",
  transform: { translation: { x: 0.1, y: 0, z: 0 }, rotation: { x: -0.5, y: 0.5, z: -0.5, w: 0.5 } } }] });
// Odometry at 100 Hz and images at 30 Hz, interleaved in time order.
const odomCount = Math.floor((frames * 100) / 30) + 10;
let k = 0, j = 0;
while (k < frames || j < odomCount) {
  const tImg = T0 + 50000000n + (BigInt(k) * 1000000000n) / 30n, tOdom = T0 + BigInt(j) * 10000000n;
  if (j < odomCount && (k >= frames || tOdom <= tImg)) {
    const s = Number(tOdom - T0) * 1e-9, yaw = 0.1 * s;
    await add("/odom", tOdom, { header: { stamp: stamp(tOdom), frame_id: "odom" }, child_frame_id: "base_link",
      pose: { pose: { position: { x: 0.5 * s, y: 0, z: 0 }, orientation: { x: 0, y: 0, z: Math.sin(yaw / 2), w: Math.cos(yaw / 2) } }, covariance: zeros(36) },
      twist: { twist: { linear: { x: 0.5, y: 0, z: 0 }, angular: { x: 0, y: 0, z: 0.1 } }, covariance: zeros(36) } });
    ++j;
  } else {
    const x = (2 * k) % (PW - W), data = new Uint8Array(W * H);
    for (let r = 0; r < H; ++r) data.set(photo.subarray((200 + r) * PW + x, (200 + r) * PW + x + W), r * W);
    const header = { stamp: stamp(tImg), frame_id: "camera_optical_frame" };
    await add("/camera/image_raw", tImg, { header, height: H, width: W, encoding: "mono8", is_bigendian: 0, step: W, data });
    await add("/camera/camera_info", tImg, { header, height: H, width: W, distortion_model: "plumb_bob", d: zeros(5),
      k: [500, 0, 320, 0, 500, 240, 0, 0, 1], r: [1, 0, 0, 0, 1, 0, 0, 0, 1], p: [500, 0, 320, 0, 0, 500, 240, 0, 0, 0, 1, 0],
      binning_x: 0, binning_y: 0, roi: { x_offset: 0, y_offset: 0, height: 0, width: 0, do_rectify: false } });
    ++k;
  }
}
await writer.end();
fs.closeSync(fd);
if (messagesFd !== undefined) fs.closeSync(messagesFd);
console.log(frames, frames / 30);
