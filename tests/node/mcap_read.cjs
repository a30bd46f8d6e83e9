// Reads an MCAP file as Foxglove and PlotJuggler do, through its indexes:
// @mcap/core's McapIndexedReader (summary, chunk indexes, message indexes,
// CRCs), then every message decoded as JSON and validated against its
// channel's JSON schema (ajv). A McapStreamReader pass with CRC validation
// reads the file front to back as well. Writes what it found as JSON.
//
//   node mcap_read.cjs FILE.mcap RESULT.json
"use strict";
const fs = require("fs");
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const Ajv = require("ajv");

async function main(path, out) {
  const bytes = fs.readFileSync(path);
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
  };
  const reader = await McapIndexedReader.Initialize({ readable });
  const ajv = new Ajv({ allErrors: true });
  const channels = {};
  const validators = new Map();
  for (const [id, c] of reader.channelsById) {
    const schema = reader.schemasById.get(c.schemaId);
    channels[c.topic] = { id, messageEncoding: c.messageEncoding, schemaName: schema.name, schemaEncoding: schema.encoding };
    validators.set(id, ajv.compile(JSON.parse(new TextDecoder().decode(schema.data))));
  }
  const counts = {}, invalid = [], order = {};
  let outOfOrder = 0, decoded = 0, minTime = null, maxTime = null;
  for await (const m of reader.readMessages()) {
    const topic = reader.channelsById.get(m.channelId).topic;
    counts[topic] = (counts[topic] || 0) + 1;
    const value = JSON.parse(new TextDecoder().decode(m.data));
    decoded++;
    const validate = validators.get(m.channelId);
    if (!validate(value) && invalid.length < 5) invalid.push(`${topic}: ${ajv.errorsText(validate.errors)}`);
    if (order[topic] !== undefined && m.logTime < order[topic]) outOfOrder++;
    order[topic] = m.logTime;
    if (minTime === null || m.logTime < minTime) minTime = m.logTime;
    if (maxTime === null || m.logTime > maxTime) maxTime = m.logTime;
  }
  const stats = reader.statistics;
  const statsCounts = {};
  for (const [id, n] of stats.channelMessageCounts) statsCounts[reader.channelsById.get(id).topic] = Number(n);

  const stream = new McapStreamReader({ validateCrcs: true });
  stream.append(bytes);
  let streamMessages = 0, dataEndCrc = null;
  for (let r; (r = stream.nextRecord()); ) {
    if (r.type === "Message") streamMessages++;
    if (r.type === "DataEnd") dataEndCrc = r.dataSectionCrc;
  }
  fs.writeFileSync(out, JSON.stringify({
    channels, counts, decoded, invalid, outOfOrder,
    minTime: minTime === null ? null : minTime.toString(), maxTime: maxTime === null ? null : maxTime.toString(),
    statistics: {
      messageCount: Number(stats.messageCount), channelCount: stats.channelCount, schemaCount: stats.schemaCount,
      chunkCount: stats.chunkCount, messageStartTime: stats.messageStartTime.toString(),
      messageEndTime: stats.messageEndTime.toString(), channelMessageCounts: statsCounts,
    },
    chunkIndexes: reader.chunkIndexes.length, streamMessages, streamDone: stream.done(), dataEndCrc,
  }));
}

main(process.argv[2], process.argv[3]).catch((e) => {
  console.error(`mcap_read: ${e.stack || e}`);
  process.exit(1);
});
