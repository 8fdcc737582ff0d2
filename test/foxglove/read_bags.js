// gear_dynamics bags read the way Foxglove Studio and Lichtblick read them: @foxglove/rosbag opens
// the file (LZ4 chunks through @foxglove/wasm-lz4), @foxglove/rosmsg parses the message definition
// stored in each connection of the bag, @foxglove/rosmsg-serialization decodes every GearState,
// RunInfo, RunSummary and PoincarePoint with it. Every field is compared with the references given in the job
// file (rosbag's Python API, the generated C++ classes, the package's batch reader).
//
//   node read_bags.js JOB.json
// JOB.json: {"groups": [{"name", "bags": [path], "references": {"python": file, "cpp": file}}],
//            "package_reader": {"group": name, "records": file, "series_csv": file}}
// A reference file maps a bag path to {"messages": [{"topic", "type", "fields"}]} (integers as
// strings, non-finite doubles as "nan"/"inf"/"-inf"). Prints a report and, last, one JSON line
// {"groups": {...}, "package_reader": {...}, "failures": [...]}; exits 1 on any difference.
"use strict";
const fs = require("fs");
const { Bag } = require("@foxglove/rosbag");
const { FileReader } = require("@foxglove/rosbag/node");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg-serialization");
const decompressLz4 = require("@foxglove/wasm-lz4");

const TYPES = ["gear_dynamics/GearState", "gear_dynamics/RunInfo", "gear_dynamics/RunSummary", "gear_dynamics/PoincarePoint"];
const INTEGER = new Set(["int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "byte", "char"]);

// A decoded value in the references' form, driven by the field's definition.
function normalise(value, field, definitions) {
  if (field.isArray) return Array.from(value, (v) => normalise(v, { ...field, isArray: false }, definitions));
  if (field.isComplex) return normaliseMessage(value, definitions.get(field.type), definitions);
  if (field.type === "float64" || field.type === "float32") {
    if (Number.isFinite(value)) return value;
    return Number.isNaN(value) ? "nan" : value > 0 ? "inf" : "-inf";
  }
  if (INTEGER.has(field.type)) return String(value);
  if (field.type === "time" || field.type === "duration") return { sec: String(value.sec), nsec: String(value.nsec) };
  return value; // bool, string
}

function normaliseMessage(message, definition, definitions) {
  const out = {};
  for (const field of definition.definitions) {
    if (field.isConstant) continue;
    out[field.name] = normalise(message[field.name], field, definitions);
  }
  return out;
}

// "a.b[3]: 1 != 2", or "" when equal (exact: numbers with Object.is, so -0 != 0).
function difference(a, b, path) {
  if (typeof a !== typeof b || Array.isArray(a) !== Array.isArray(b) || (a === null) !== (b === null)) {
    return `${path}: ${JSON.stringify(a)} != ${JSON.stringify(b)}`;
  }
  if (Array.isArray(a)) {
    if (a.length !== b.length) return `${path}: length ${a.length} != ${b.length}`;
    for (let i = 0; i < a.length; i++) {
      const d = difference(a[i], b[i], `${path}[${i}]`);
      if (d) return d;
    }
    return "";
  }
  if (typeof a === "object") {
    const ka = Object.keys(a), kb = Object.keys(b);
    if (ka.join() !== kb.join()) return `${path}: fields ${ka} != ${kb}`;
    for (const k of ka) {
      const d = difference(a[k], b[k], path ? `${path}.${k}` : k);
      if (d) return d;
    }
    return "";
  }
  return Object.is(a, b) ? "" : `${path}: ${JSON.stringify(a)} != ${JSON.stringify(b)}`;
}

// Every message of the three types in the bag, decoded twice: with the definitions parsed here
// (rosmsg + rosmsg-serialization) and as @foxglove/rosbag's own iterator parses it; they must agree.
async function readBag(path) {
  const chunks = { lz4: 0, bz2: 0 };
  const file = new FileReader(path);
  const bag = new Bag(file, {
    decompress: {
      lz4: (buffer, size) => { chunks.lz4++; return decompressLz4(buffer, size); },
      bz2: () => { chunks.bz2++; throw new Error("bz2 chunks: no decompressor in this test"); },
    },
  });
  await bag.open();
  const decoders = new Map(); // connection id -> {type, definitions, root, reader}
  for (const [id, c] of bag.connections) {
    const defs = parse(c.messageDefinition);
    const definitions = new Map(defs.filter((d) => d.name).map((d) => [d.name, d]));
    decoders.set(id, { type: c.type, root: defs[0], definitions, reader: new MessageReader(defs) });
  }
  const messages = [];
  const fields = {};
  for await (const event of bag.messageIterator()) {
    const dec = decoders.get(event.connectionId);
    if (!dec || !TYPES.includes(dec.type)) continue;
    const decoded = normaliseMessage(dec.reader.readMessage(event.data), dec.root, dec.definitions);
    const byBag = normaliseMessage(event.message, dec.root, dec.definitions);
    const d = difference(decoded, byBag, "");
    if (d) throw new Error(`${path}: rosmsg-serialization and rosbag's parse disagree on ${event.topic}: ${d}`);
    const t = event.timestamp; // the receive time of the bag record
    messages.push({ topic: event.topic, type: dec.type, time: { sec: String(t.sec), nsec: String(t.nsec) }, fields: decoded });
    fields[dec.type] ??= dec.root.definitions.filter((f) => !f.isConstant).map((f) =>
      f.isComplex ? `${f.name}{${dec.definitions.get(f.type).definitions.filter((g) => !g.isConstant).map((g) => g.name).join(",")}}`
                  : f.name + (f.isArray ? "[]" : ""));
  }
  await file.close();
  return { messages, chunks, chunkCount: bag.chunkInfos.length, fields };
}

// Topic by topic, each sorted by (receive time, header.seq). Messages with the same receive time
// have no order a reader must keep: the live bags have many (rosbag record stamps them with
// /clock, which the simulator at real_time_factor 0 advances in jumps), and @foxglove/rosbag
// yields those of one topic in another order than rosbag's Python and C++ APIs (a heap merge).
// `reordered` counts them.
// PoincarePoint has no header: its receive times differ (one point per mesh period).
const key = (m) => [BigInt(m.time.sec), BigInt(m.time.nsec), BigInt(m.fields.header ? m.fields.header.seq : 0)];
function canonical(list) {
  return [...list].sort((a, b) => {
    const ka = key(a), kb = key(b);
    for (let i = 0; i < 3; i++) if (ka[i] !== kb[i]) return ka[i] < kb[i] ? -1 : 1;
    return 0;
  });
}
function byTopic(messages) {
  const out = new Map();
  for (const m of messages) {
    if (!out.has(m.topic)) out.set(m.topic, []);
    out.get(m.topic).push(m);
  }
  for (const [t, list] of out) out.set(t, canonical(list));
  return out;
}
function reordered(messages) {
  let n = 0;
  const last = new Map();
  for (const m of messages) {
    const prev = last.get(m.topic);
    if (prev && key(prev)[0] === key(m)[0] && key(prev)[1] === key(m)[1] && key(prev)[2] > key(m)[2]) n++;
    last.set(m.topic, m);
  }
  return n;
}

function compareMessages(got, want, label) {
  if (got.length !== want.length) return `${label}: ${got.length} messages, reference ${want.length}`;
  const g = byTopic(got), w = byTopic(want);
  if ([...g.keys()].sort().join() !== [...w.keys()].sort().join()) return `${label}: topics ${[...g.keys()]} != ${[...w.keys()]}`;
  for (const [topic, gs] of g) {
    const ws = w.get(topic);
    if (gs.length !== ws.length) return `${label}: ${gs.length} messages on ${topic}, reference ${ws.length}`;
    for (let i = 0; i < gs.length; i++) {
      if (gs[i].type !== ws[i].type) return `${label}: ${topic} message ${i} is ${gs[i].type}, reference ${ws[i].type}`;
      const d = difference(gs[i].fields, ws[i].fields, "");
      const dt = difference(gs[i].time, ws[i].time, "receive time");
      if (d || dt) return `${label}: ${topic} message ${i} (${gs[i].type}): ${d || dt}`;
    }
  }
  return "";
}

// RunSummary against the package's own batch reader (one record per run), GearState against the
// series CSV it writes for S1, S2 and S3 (paper units, 10 significant digits).
function comparePackageReader(bags, job) {
  const ref = JSON.parse(fs.readFileSync(job.records, "utf8"));
  const records = new Map(ref.runs.map((r) => [r.name, r]));
  const series = new Map();
  for (const line of fs.readFileSync(job.series_csv, "utf8").split("\n")) {
    const c = line.split(",");
    if (c.length !== 8 || Number.isNaN(Number(c[4]))) continue; // header or blank
    if (!series.has(c[0])) series.set(c[0], []);
    series.get(c[0]).push(c.slice(4).map(Number));
  }
  const k = ref.to_paper_units;
  const failures = [];
  let summaries = 0, states = 0;
  const fieldMap = [["kind", "kind"], ["realization", "index"], ["mu", "mu"], ["center_distance", "center_distance"],
    ["steady_state_time", "steady_state_time"], ["steady_state_time_fine", "steady_state_time_fine"],
    ["reached_steady_state", "reached_steady_state"], ["final_delta", "final_delta"],
    ["final_delta_dot", "final_delta_dot"], ["final_phi", "final_phi"], ["snapshot_times", "snapshot_times"],
    ["snapshot_delta", "snapshot_delta"], ["snapshot_delta_dot", "snapshot_delta_dot"]];
  for (const [path, r] of bags) {
    for (const m of r.messages.filter((m) => m.type === "gear_dynamics/RunSummary")) {
      const rec = records.get(m.fields.run_name);
      if (!rec) { failures.push(`${path}: run ${m.fields.run_name} not among the batch reader's records`); continue; }
      for (const [f, g] of fieldMap) {
        const d = difference(m.fields[f], rec[g], `${m.fields.run_name}.${f}`);
        if (d) failures.push(`package reader: ${d}`);
      }
      summaries++;
      const rows = series.get(m.fields.run_name);
      if (!rows) continue;
      const st = r.messages.filter((x) => x.type === "gear_dynamics/GearState").map((x) => x.fields);
      if (rows.length !== st.length) { failures.push(`${m.fields.run_name}: ${st.length} GearState, series.csv ${rows.length} rows`); continue; }
      st.forEach((s, i) => {
        const want = [s.t, s.delta * k, s.delta_dot * k, s.phi * k];
        rows[i].forEach((v, j) => {
          if (Math.abs(v - want[j]) > 1e-9 * Math.max(Math.abs(want[j]), 1e-300) + 1e-300) {
            failures.push(`${m.fields.run_name} state ${i} column ${j}: series.csv ${v}, decoded ${want[j]}`);
          }
        });
        states++;
      });
    }
  }
  if (summaries !== records.size) failures.push(`${summaries} RunSummary decoded, the batch reader has ${records.size} records`);
  return { summaries, records: records.size, series_runs: series.size, series_states: states, failures: failures.slice(0, 20) };
}

async function main() {
  await decompressLz4.isLoaded;
  const job = JSON.parse(fs.readFileSync(process.argv[2], "utf8"));
  const result = { groups: {}, failures: [] };
  const read = new Map();
  for (const group of job.groups) {
    const refs = Object.fromEntries(Object.entries(group.references).map(([k, f]) => [k, JSON.parse(fs.readFileSync(f, "utf8"))]));
    const g = { bags: group.bags.length, messages: {}, lz4_chunks: 0, chunks: 0, fields: {}, compared_with: Object.keys(refs),
                yielded_out_of_seq_order: 0 };
    for (const path of group.bags) {
      let r;
      try {
        r = await readBag(path);
      } catch (e) {
        result.failures.push(`${group.name}: ${e.message}`);
        continue;
      }
      read.set(path, r);
      g.lz4_chunks += r.chunks.lz4;
      g.chunks += r.chunkCount;
      Object.assign(g.fields, r.fields);
      for (const m of r.messages) g.messages[m.type] = (g.messages[m.type] ?? 0) + 1;
      g.yielded_out_of_seq_order += reordered(r.messages);
      for (const [name, ref] of Object.entries(refs)) {
        if (!ref[path]) { result.failures.push(`${group.name}: no ${name} reference for ${path}`); continue; }
        const d = compareMessages(r.messages, ref[path].messages, `${path} vs ${name}`);
        if (d) result.failures.push(d);
      }
    }
    result.groups[group.name] = g;
    console.log(`${group.name}: ${g.bags} bags, ${g.chunks} chunks (${g.lz4_chunks} LZ4), messages ${JSON.stringify(g.messages)}, compared with ${g.compared_with.join(", ")}; ${g.yielded_out_of_seq_order} yielded before a lower header.seq of the same topic and receive time`);
  }
  if (job.package_reader) {
    const bags = [...read].filter(([p]) => job.groups.find((g) => g.name === job.package_reader.group).bags.includes(p));
    const p = comparePackageReader(bags, job.package_reader);
    result.failures.push(...p.failures);
    delete p.failures;
    result.package_reader = p;
    console.log(`package reader: ${p.summaries} RunSummary against ${p.records} records, ${p.series_states} GearState against series.csv (${p.series_runs} runs)`);
  }
  for (const f of result.failures.slice(0, 30)) console.log("DIFFERENCE: " + f);
  console.log(JSON.stringify(result));
  process.exit(result.failures.length ? 1 : 0);
}

main().catch((e) => {
  console.error(e);
  console.log(JSON.stringify({ failures: [String(e && e.stack || e)] }));
  process.exit(1);
});
