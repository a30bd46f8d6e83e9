// Operator commands signed in the browser, exactly as `rigctl cmd` signs
// them (docs/operator-commands.md, rt/comms/operator_auth.hpp): HMAC-SHA256
// (WebCrypto) over the canonical encoding
//   "rigctl.operator_command.v1" 0x00 | version int32 | sender string |
//   sequence int64 | utime int64 | command string | value binary64 bits
// (big-endian; strings as a uint32 byte count then UTF-8 bytes). The key is
// typed by the operator as hex and only ever passed to WebCrypto: never
// sent, never stored.
"use strict";
window.rigctl = window.rigctl || {};

rigctl.signing = (() => {
  const encoder = new TextEncoder();
  const LABEL = "rigctl.operator_command.v1";

  function canonicalBytes(c) {
    const label = encoder.encode(LABEL);
    const sender = encoder.encode(c.sender);
    const command = encoder.encode(c.command);
    const size = label.length + 1 + 4 + 4 + sender.length + 8 + 8 + 4 + command.length + 8;
    const out = new Uint8Array(size);
    const view = new DataView(out.buffer);
    let at = 0;
    const bytes = (b) => { out.set(b, at); at += b.length; };
    const string = (b) => { view.setUint32(at, b.length); at += 4; bytes(b); };
    bytes(label);
    out[at++] = 0;
    view.setInt32(at, c.version); at += 4;
    string(sender);
    view.setBigInt64(at, BigInt(c.sequence)); at += 8;
    view.setBigInt64(at, BigInt(c.utime)); at += 8;
    string(command);
    view.setFloat64(at, c.value); at += 8;  // big-endian binary64: the bit pattern as uint64
    return out;
  }

  // "00 1f ..." or "001f...": at least 32 bytes, as the rig's key file.
  function parseKey(text) {
    const hex = text.replace(/\s+/g, "");
    if (!/^([0-9a-fA-F]{2})+$/.test(hex)) throw new Error("the key is not hex digits");
    if (hex.length < 64) throw new Error("the key is shorter than 32 bytes");
    const out = new Uint8Array(hex.length / 2);
    for (let i = 0; i < out.length; ++i) out[i] = parseInt(hex.substr(2 * i, 2), 16);
    return out;
  }

  const toHex = (bytes) => Array.from(bytes, (b) => b.toString(16).padStart(2, "0")).join("");

  async function sign(keyText, c) {
    if (!window.crypto || !crypto.subtle) throw new Error("WebCrypto needs https or localhost: see docs/console.md");
    const key = await crypto.subtle.importKey("raw", parseKey(keyText), { name: "HMAC", hash: "SHA-256" }, false, ["sign"]);
    const tag = await crypto.subtle.sign("HMAC", key, canonicalBytes(c));
    return toHex(new Uint8Array(tag));
  }

  return { canonicalBytes, parseKey, sign, toHex };
})();
