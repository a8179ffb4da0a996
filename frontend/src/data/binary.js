/**
 * Parser of the binary timeline (docs/API.md "Binary timeline"):
 *
 *   offset 0   4 bytes  magic "AHTL"
 *          4   u32 LE   format version (1)
 *          8   u32 LE   header length H
 *         12   H bytes  UTF-8 JSON header {n_ticks, tick_s, revision, blocks: [{name, dtype, shape, offset, scale}]}
 *     12 + H   blocks, 4-byte aligned, little-endian, at the header's offsets
 *
 * Blocks are returned as typed-array views on the same buffer (no copy).
 */

export const MAGIC = "AHTL";
export const BIN_VERSION = 1;

/**
 * @typedef {{name: string, dtype: string, shape: number[], offset: number, scale?: number|null}} BlockInfo
 * @typedef {{n_ticks: number, tick_s: number, revision: number, blocks: BlockInfo[], [key: string]: any}} BinHeader
 * @typedef {{header: BinHeader, blocks: Map<string, {info: BlockInfo, data: Uint8Array|Float32Array|Int16Array|Uint16Array|Int32Array}>}} ParsedBin
 */

const TYPES = /** @type {const} */ ({
  u8: [Uint8Array, 1],
  uint8: [Uint8Array, 1],
  u16: [Uint16Array, 2],
  uint16: [Uint16Array, 2],
  i16: [Int16Array, 2],
  int16: [Int16Array, 2],
  i32: [Int32Array, 4],
  int32: [Int32Array, 4],
  f32: [Float32Array, 4],
  float32: [Float32Array, 4],
});

/**
 * @param {ArrayBuffer} buf
 * @returns {ParsedBin}
 */
export function parseTimelineBin(buf) {
  if (buf.byteLength < 12) throw new Error(`binary timeline too short (${buf.byteLength} bytes)`);
  const dv = new DataView(buf);
  const magic = String.fromCharCode(dv.getUint8(0), dv.getUint8(1), dv.getUint8(2), dv.getUint8(3));
  if (magic !== MAGIC) throw new Error(`not a binary timeline: magic ${JSON.stringify(magic)}, expected "AHTL"`);
  const version = dv.getUint32(4, true);
  if (version !== BIN_VERSION) throw new Error(`binary timeline version ${version} is not supported (expected 1)`);
  const hlen = dv.getUint32(8, true);
  if (12 + hlen > buf.byteLength) throw new Error(`binary timeline header (${hlen} bytes) overruns the file`);
  /** @type {BinHeader} */
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 12, hlen)));
  const blocks = new Map();
  for (const info of header.blocks || []) {
    const t = TYPES[/** @type {keyof typeof TYPES} */ (String(info.dtype).toLowerCase())];
    if (!t) throw new Error(`binary timeline block ${info.name}: unknown dtype ${info.dtype}`);
    const [Ctor, size] = t;
    const count = info.shape.reduce((a, b) => a * b, 1);
    if (info.offset % size !== 0) throw new Error(`binary timeline block ${info.name} is misaligned (offset ${info.offset})`);
    if (info.offset + count * size > buf.byteLength) {
      throw new Error(`binary timeline block ${info.name} (${count} x ${info.dtype}) overruns the file`);
    }
    blocks.set(info.name, { info, data: new Ctor(buf, info.offset, count) });
  }
  return { header, blocks };
}
