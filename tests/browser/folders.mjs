// Small folders in the DMBN layout for the folder tests, written from the web package's own
// simulator (so they need nothing but pkg/): frames as PNG, the text files as `dmbn simulate`
// writes them, and broken variants of them.
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

/** An RGB8 PNG of `size`×`size` pixels (no filtering). */
export function png(rgb, size) {
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
  header.writeUInt32BE(size, 4);
  header.set([8, 2, 0, 0, 0], 8);
  const raw = Buffer.alloc(size * (size * 3 + 1));
  for (let y = 0; y < size; y++) Buffer.from(rgb.buffer, rgb.byteOffset + y * size * 3, size * 3).copy(raw, y * (size * 3 + 1) + 1);
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
 */
export function folderFiles(wasm, root, episodes, size = 64) {
  const files = {};
  const digests = {};
  const text = (s) => Buffer.from(s);
  episodes.forEach(({ action, seed, id = seed }) => {
    const ep = wasm.runEpisode(action, seed, size);
    const dir = `${root}/${id}/${action}`;
    const frames = ep.frames();
    const px = size * size * 3;
    for (let k = 0; k < ep.len; k++) files[`${dir}/${k}.png`] = png(frames.subarray(k * px, (k + 1) * px), size);
    files[`${dir}/joint_${id}.txt`] = text(table(ep.joints(), 7));
    files[`${dir}/object_${id}.txt`] = text(table(ep.object(), 3));
    files[`${dir}/endpoint_${id}.txt`] = text(table(ep.endpoint(), 7));
    digests[`${id}/${action}`] = ep.digest();
    ep.free();
  });
  return { files, digests };
}

/**
 * Writes the episodes `[{action, seed}]` of the wasm package `wasm` at `size` px as sequences
 * 0, 1, … of a folder at `root` (replaced); returns their digests by "id/action".
 */
export function writeFolder(wasm, root, episodes, size = 64) {
  rmSync(root, { recursive: true, force: true });
  const { files, digests } = folderFiles(wasm, ".", episodes, size);
  for (const [path, bytes] of Object.entries(files)) {
    mkdirSync(dirname(join(root, path)), { recursive: true });
    writeFileSync(join(root, path), bytes);
  }
  return digests;
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
