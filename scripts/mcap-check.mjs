// Reads an MCAP file with readers lmd did not write (npm's @mcap/core, and
// @foxglove/rosmsg + @foxglove/rosmsg2-serialization for the ros2msg schemas
// and CDR), and prints what it found as one JSON object: per topic its schema
// name, message count and a few decoded fields. Exits 1 on any error.
// Usage: LMD_MCAP_CHECK_DIR=DIR node scripts/mcap-check.mjs FILE.mcap
// (DIR holds node_modules; scripts/mcap-check-install.sh fills it).
import { createRequire } from "node:module";
import { readFile } from "node:fs/promises";

const dir = process.env.LMD_MCAP_CHECK_DIR;
if (!dir) throw new Error("set LMD_MCAP_CHECK_DIR to the folder holding node_modules");
const require = createRequire(dir.replace(/\/?$/, "/") + "node_modules/");
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");

const bytes = new Uint8Array(await readFile(process.argv[2]));

// 1. Every record, CRCs validated, through the streaming reader.
const stream = new McapStreamReader({ validateCrcs: true });
stream.append(bytes);
let records = 0;
for (let r; (r = stream.nextRecord()) !== undefined; ) records++;
if (!stream.done()) throw new Error("the stream reader did not reach the end magic");

// 2. The summary, chunk indexes and messages through the indexed reader.
const readable = {
  size: async () => BigInt(bytes.length),
  read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
};
const reader = await McapIndexedReader.Initialize({ readable });
const decoders = new Map();
const topics = {};
for await (const message of reader.readMessages()) {
  const channel = reader.channelsById.get(message.channelId);
  const schema = reader.schemasById.get(channel.schemaId);
  if (!decoders.has(schema.id)) {
    decoders.set(schema.id, new MessageReader(parse(new TextDecoder().decode(schema.data), { ros2: true })));
  }
  const m = decoders.get(schema.id).readMessage(message.data);
  const t = (topics[channel.topic] ??= { schema: schema.name, encoding: channel.messageEncoding, messages: 0 });
  t.messages++;
  if (schema.name === "sensor_msgs/msg/PointCloud2") {
    t.frame_id = m.header.frame_id;
    t.points = m.width;
    t.fields = m.fields.map((f) => f.name).join(",");
    const view = new DataView(m.data.buffer, m.data.byteOffset, m.data.byteLength);
    if (m.width > 0) t.first_point = [view.getFloat32(0, true), view.getFloat32(4, true)];
  } else if (schema.name === "nav_msgs/msg/Path") {
    t.frame_id = m.header.frame_id;
    t.poses = m.poses.length;
  } else if (schema.name === "visualization_msgs/msg/MarkerArray") {
    t.markers = m.markers.length;
    t.texts = m.markers.filter((k) => k.text).map((k) => k.text);
  } else if (schema.name === "tf2_msgs/msg/TFMessage") {
    t.transforms = m.transforms.map((k) => `${k.header.frame_id} -> ${k.child_frame_id}`);
    t.qos = channel.metadata.get("offered_qos_profiles")?.includes("durability: 1") ? "transient local" : "volatile";
  }
}
console.log(JSON.stringify({ records, chunks: reader.chunkIndexes.length, topics }));
