// A model file of another robot for the browser tests, made from a shipped one without training:
// a DMBN-PTE file (`assets/models/pte-sim.dmbn`) widened from 7 joint values a step to more.
// The joint encoder's first layer gets a zero row for each new input (the new values are read
// and ignored), the joint decoder's mean and σ heads a copy of the gripper's column for each new
// output, the normalisation mean 0 and std 1 for them; every other weight stays. Its predictions
// of the old values are the old model's; it is only for testing a page that sizes everything by
// `Model.jointCount`.
//
// The model file (crate/model/file.rs): "DMBNMODL", version u32, header length u32, the JSON
// header, weights length u64, the weights: a burnpack ("NRUB", version u16, metadata length
// u32, CBOR metadata {tensors: {name: {dtype, shape, data_offsets, param_id}}, metadata}, then
// the tensors' data, each at a multiple of 256 from the data's start). The widened tensors'
// data go after the others', and only their shapes and offsets change in the metadata, in place
// (the same CBOR sizes), so that nothing else moves.
import { createHash } from "node:crypto";

/** The tensors of a DMBN-PTE model that hold one entry per joint value, and along which axis. */
const JOINT_AXES = {
  "network.Pte.joint_encoder.layers.0.weight": { axis: 0, fill: "zero" },
  "network.Pte.decoder.joint.mean.weight": { axis: 1, fill: "last" },
  "network.Pte.decoder.joint.mean.bias": { axis: 0, fill: "last" },
  "network.Pte.decoder.joint.sigma.weight": { axis: 1, fill: "last" },
  "network.Pte.decoder.joint.sigma.bias": { axis: 0, fill: "last" },
};
const ALIGN = 256;

/**
 * A minimal CBOR reader (the subset burnpack writes) that keeps, for every integer, where its
 * encoding is: `{value, at, size}`, so that it can be overwritten in place.
 */
function readCbor(bytes, start) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  let i = start;
  const item = () => {
    const at = i;
    const head = bytes[i++];
    const major = head >> 5;
    const extra = head & 31;
    let n;
    if (extra < 24) n = BigInt(extra);
    else if (extra === 24) n = BigInt(bytes[i++]);
    else if (extra === 25) (n = BigInt(view.getUint16(i))), (i += 2);
    else if (extra === 26) (n = BigInt(view.getUint32(i))), (i += 4);
    else if (extra === 27) (n = view.getBigUint64(i)), (i += 8);
    else throw new Error(`CBOR: unsupported head ${head} at ${at}`);
    const count = Number(n);
    switch (major) {
      case 0:
        return { value: count, big: n, at, size: i - at };
      case 2:
        i += count;
        return bytes.subarray(i - count, i);
      case 3:
        i += count;
        return Buffer.from(bytes.subarray(i - count, i)).toString("utf8");
      case 4:
        return Array.from({ length: count }, item);
      case 5: {
        const out = {};
        for (let k = 0; k < count; k++) {
          const key = item();
          out[typeof key === "string" ? key : String(key.value)] = item();
        }
        return out;
      }
      case 7:
        return { value: count, at, size: i - at };
      default:
        throw new Error(`CBOR: unsupported major type ${major} at ${at}`);
    }
  };
  return item();
}

/** Overwrites the CBOR integer `int` (as readCbor found it) with `value`, in the same size. */
function writeInt(bytes, int, value) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const fits = { 1: value < 24, 2: value < 256, 3: value < 65536, 5: value < 2 ** 32 }[int.size];
  if (!fits) throw new Error(`CBOR: ${value} does not fit the ${int.size} bytes of ${int.value}`);
  if (int.size === 1) bytes[int.at] = value;
  else if (int.size === 2) bytes[int.at + 1] = value;
  else if (int.size === 3) view.setUint16(int.at + 1, value);
  else view.setUint32(int.at + 1, value);
}

/**
 * The DMBN-PTE model file `file` (bytes) widened to `joints` joint values a step, named
 * `names` (optional). Throws when the file is not a 7-value DMBN-PTE model of this layout.
 */
export function widenModel(file, joints, names = null) {
  const bytes = new Uint8Array(file);
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (Buffer.from(bytes.subarray(0, 8)).toString("latin1") !== "DMBNMODL") throw new Error("not a model file");
  const headerLength = view.getUint32(12, true);
  const header = JSON.parse(Buffer.from(bytes.subarray(16, 16 + headerLength)).toString("utf8"));
  const weightsAt = 24 + headerLength;
  const weightsLength = Number(view.getBigUint64(16 + headerLength, true));
  const weights = new Uint8Array(bytes.subarray(weightsAt, weightsAt + weightsLength));
  const d = header.config.joints ?? 7;
  if (header.config.kind !== "pte" || d !== 7) throw new Error(`expected a DMBN-PTE model of 7 joint values, got ${header.config.kind} of ${d}`);
  if (Buffer.from(weights.subarray(0, 4)).toString("latin1") !== "NRUB") throw new Error("the weights are not a burnpack");
  const wview = new DataView(weights.buffer, weights.byteOffset, weights.byteLength);
  const metaLength = wview.getUint32(6, true);
  const dataAt = Math.ceil((10 + metaLength) / ALIGN) * ALIGN;
  const meta = readCbor(weights, 10);
  const data = weights.subarray(dataAt);
  const extra = [];
  let end = Math.ceil(data.length / ALIGN) * ALIGN;
  let added = 0;
  for (const [name, { axis, fill }] of Object.entries(JOINT_AXES)) {
    const t = meta.tensors[name];
    if (!t) throw new Error(`the model has no tensor ${name}`);
    const shape = t.shape.map((s) => s.value);
    const [from, to] = t.data_offsets.map((o) => o.value);
    const bytesPer = { F16: 2, F32: 4 }[t.dtype];
    if (!bytesPer || shape[axis] !== d) throw new Error(`${name}: unexpected ${t.dtype} ${shape}`);
    const rows = shape.length === 2 ? shape[0] : 1;
    const cols = shape.length === 2 ? shape[1] : shape[0];
    const old = data.subarray(from, to);
    const wide = shape.slice();
    wide[axis] = joints;
    const [newRows, newCols] = shape.length === 2 ? wide : [1, wide[0]];
    const out = new Uint8Array(newRows * newCols * bytesPer);
    for (let r = 0; r < newRows; r++) {
      for (let c = 0; c < newCols; c++) {
        const sr = Math.min(r, rows - 1);
        const sc = Math.min(c, cols - 1);
        const isNew = r >= rows || c >= cols;
        if (isNew && fill === "zero") continue;
        const src = (sr * cols + sc) * bytesPer;
        out.set(old.subarray(src, src + bytesPer), (r * newCols + c) * bytesPer);
      }
    }
    added += (newRows * newCols) - rows * cols;
    // Shapes in place (single-byte integers: 7 → joints), offsets to the data appended.
    t.shape.forEach((s, k) => writeInt(weights, s, wide[k]));
    writeInt(weights, t.data_offsets[0], end);
    writeInt(weights, t.data_offsets[1], end + out.length);
    extra.push({ at: end, out });
    end = Math.ceil((end + out.length) / ALIGN) * ALIGN;
  }
  const newData = new Uint8Array(end);
  newData.set(data);
  for (const { at, out } of extra) newData.set(out, at);
  const newWeights = new Uint8Array(dataAt + newData.length);
  newWeights.set(weights.subarray(0, dataAt));
  newWeights.set(newData, dataAt);
  // The header: joints, names, normalisation, and the weights' length, checksum, parameters.
  const { mean, std } = header.normalization;
  header.config.joints = joints;
  if (names) header.config.joint_names = names;
  header.normalization = { mean: [...mean, ...Array(joints - d).fill(0)], std: [...std, ...Array(joints - d).fill(1)] };
  header.weights.bytes = newWeights.length;
  header.weights.sha256 = createHash("sha256").update(newWeights).digest("hex");
  header.weights.parameters += added;
  const json = Buffer.from(JSON.stringify(header, null, 2));
  const out = Buffer.alloc(24 + json.length + newWeights.length);
  out.write("DMBNMODL", 0, "latin1");
  out.writeUInt32LE(view.getUint32(8, true), 8);
  out.writeUInt32LE(json.length, 12);
  json.copy(out, 16);
  out.writeBigUInt64LE(BigInt(newWeights.length), 16 + json.length);
  out.set(newWeights, 24 + json.length);
  return out;
}
