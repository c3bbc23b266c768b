// Small folders in the DMBN layout for the folder tests, written from the web package's own
// simulator (so they need nothing but pkg/): frames as PNG, the text files as `dmbn simulate`
// writes them, and broken variants of them; and made-up data of another robot (more joint
// values a step, frames of another size, no object or endpoint files).
import { mkdirSync, rmSync, unlinkSync, writeFileSync } from "node:fs";
import { dirname, join } from "node:path";
import { deflateSync } from "node:zlib";

const CRC_TABLE = Array.from({ length: 256 }, (_, n) => {
  let c = n;
  for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c >>> 0;
});
const crc32 = (bytes) => {
  let c = 0xffffffff;
  for (const b of bytes) c = CRC_TABLE[(c ^ b) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
};

/** An RGB8 PNG of `size`×`height` pixels (square by default; no filtering). */
export function png(rgb, size, height = size) {
  const chunk = (type, data) => {
    const out = Buffer.alloc(12 + data.length);
    out.writeUInt32BE(data.length, 0);
    out.write(type, 4, "latin1");
    data.copy(out, 8);
    out.writeUInt32BE(crc32(out.subarray(4, 8 + data.length)), 8 + data.length);
    return out;
  };
  const header = Buffer.alloc(13);
  header.writeUInt32BE(size, 0);
  header.writeUInt32BE(height, 4);
  header.set([8, 2, 0, 0, 0], 8);
  const raw = Buffer.alloc(height * (size * 3 + 1));
  for (let y = 0; y < height; y++) Buffer.from(rgb.buffer, rgb.byteOffset + y * size * 3, size * 3).copy(raw, y * (size * 3 + 1) + 1);
  return Buffer.concat([Buffer.from([137, 80, 78, 71, 13, 10, 26, 10]), chunk("IHDR", header), chunk("IDAT", deflateSync(raw)), chunk("IEND", Buffer.alloc(0))]);
}

/** A number as text that reads back to the same f32 (JS's shortest round trip; -0 kept). */
const number = (v) => (Object.is(v, -0) ? "-0" : String(v));
/** Rows of `width` numbers, one line per step. */
const table = (values, width) =>
  Array.from({ length: values.length / width }, (_, k) => Array.from(values.subarray(k * width, (k + 1) * width), number).join(" ") + "\n").join("");

/**
 * The files of the episodes `[{action, seed}]` of the wasm package `wasm` at `size` px as
 * sequences 0, 1, … of a folder named `root`: `{files: {path: bytes}, digests: {"id/action": digest}}`.
 * `arm`: the simulator's arm ("ur5", the default, or "panda": 8 joint values a step).
 */
export function folderFiles(wasm, root, episodes, size = 64, { object = true, arm = "ur5" } = {}) {
  const files = {};
  const digests = {};
  const text = (s) => Buffer.from(s);
  episodes.forEach(({ action, seed, id = seed }) => {
    const ep = wasm.runEpisode(action, seed, size, arm);
    const dir = `${root}/${id}/${action}`;
    const frames = ep.frames();
    const px = size * size * 3;
    for (let k = 0; k < ep.len; k++) files[`${dir}/${k}.png`] = png(frames.subarray(k * px, (k + 1) * px), size);
    files[`${dir}/joint_${id}.txt`] = text(table(ep.joints(), ep.jointCount));
    if (object) {
      files[`${dir}/object_${id}.txt`] = text(table(ep.object(), 3));
      files[`${dir}/endpoint_${id}.txt`] = text(table(ep.endpoint(), 7));
    }
    digests[`${id}/${action}`] = ep.digest();
    ep.free();
  });
  return { files, digests };
}

/** Writes `files` ({path: bytes}, relative) into a folder at `root` (replaced). */
function writeFiles(root, files) {
  rmSync(root, { recursive: true, force: true });
  for (const [path, bytes] of Object.entries(files)) {
    mkdirSync(dirname(join(root, path)), { recursive: true });
    writeFileSync(join(root, path), bytes);
  }
}

/**
 * Writes the episodes `[{action, seed}]` of the wasm package `wasm` at `size` px as sequences
 * 0, 1, … of a folder at `root` (replaced); returns their digests by "id/action". `object:
 * false` leaves out the object and endpoint files (data that has none); `arm` as folderFiles.
 */
export function writeFolder(wasm, root, episodes, size = 64, { object = true, arm = "ur5" } = {}) {
  const { files, digests } = folderFiles(wasm, ".", episodes, size, { object, arm });
  writeFiles(root, files);
  return digests;
}

/**
 * Writes a folder at `root` (replaced) of another robot's data, made up: sequences `ids` of
 * `action`, `steps` steps each, `joints` joint values a step (smooth curves, the last one a
 * gripper opening and closing) and `width`×`height` PNG frames (a gradient that moves), no
 * object or endpoint files.
 */
export function writeRobotFolder(root, { ids = [0, 1], action = "move", steps = 12, joints = 8, width = 40, height = 30 } = {}) {
  const files = {};
  for (const id of ids) {
    const dir = `${id}/${action}`;
    const rows = [];
    for (let k = 0; k < steps; k++) {
      const phase = k / (steps - 1);
      const row = Array.from({ length: joints }, (_, j) =>
        j + 1 === joints ? (phase < 0.5 ? 0.04 : 0) : 0.5 * Math.sin(2 * Math.PI * phase + j + id) + 0.1 * j,
      );
      rows.push(row.map((v) => v.toFixed(5)).join(" ") + "\n");
      const rgb = new Uint8Array(width * height * 3);
      for (let y = 0; y < height; y++) {
        for (let x = 0; x < width; x++) {
          const i = (y * width + x) * 3;
          rgb[i] = (x * 255) / (width - 1);
          rgb[i + 1] = (y * 255) / (height - 1);
          rgb[i + 2] = Math.abs(x - phase * (width - 1)) < 4 ? 255 : 40 * id;
        }
      }
      files[`${dir}/${k}.png`] = png(rgb, width, height);
    }
    files[`${dir}/joint_${id}.txt`] = Buffer.from(rows.join(""));
  }
  writeFiles(root, files);
}

/**
 * Broken copies of a one-sequence folder (sequence 0 of grasp), each with the message the
 * reader gives, the path inside the folder first: what the page must show.
 */
export function writeBrokenFolders(wasm, base) {
  const cases = {
    "no-sequences": (dir) => {
      rmSync(join(dir, "0"), { recursive: true });
      writeFileSync(join(dir, "LICENSE"), "MIT");
      return /^no-sequences: no sequences found: expected numeric id folders/;
    },
    "missing-joints": (dir) => {
      unlinkSync(join(dir, "0", "grasp", "joint_0.txt"));
      return /^missing-joints\/0\/grasp\/joint_0\.txt: no such file$/;
    },
    "malformed-row": (dir) => {
      const path = join(dir, "0", "grasp", "joint_0.txt");
      writeFileSync(path, "0 0 0 0 0 0 0\n1 2 x\n");
      return /^malformed-row\/0\/grasp\/joint_0\.txt line 2: expected 7 columns, found 3$/;
    },
    "few-frames": (dir) => {
      unlinkSync(join(dir, "0", "grasp", "3.png"));
      return /^few-frames\/0\/grasp: frame 3 is missing: expected 3\.png or 3\.jpeg/;
    },
    "not-an-image": (dir) => {
      writeFileSync(join(dir, "0", "grasp", "2.png"), "not a picture");
      return /^not-an-image\/0\/grasp\/2\.png: cannot decode frame/;
    },
  };
  return Object.entries(cases).map(([name, breakIt]) => {
    const dir = join(base, name);
    writeFolder(wasm, dir, [{ action: "grasp", seed: 3, id: 0 }]);
    return { name, dir, message: breakIt(dir) };
  });
}
