#!/usr/bin/env bash
# The README's pictures: runs the demo (scripts/demo.sh: a simulated traverse replayed through
# the mapper) into a scratch folder and copies its dem.png, drift.png and terrain.png to docs/img/, their
# image data deflated again at the highest level (the same pixels, about half the bytes).
#
#   scripts/make_doc_images.sh BUILD/apps/rovermap
set -euo pipefail
bin=${1:?usage: make_doc_images.sh ROVERMAP_BINARY}
root="$(cd "$(dirname "$0")/.." && pwd)"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

bash "$root/scripts/demo.sh" "$bin" "$scratch/demo" > "$scratch/demo.log" 2>&1 ||
  { cat "$scratch/demo.log" >&2; exit 1; }
mkdir -p "$root/docs/img"
for name in dem drift terrain; do
  python3 - "$scratch/demo/replay/$name.png" "$root/docs/img/$name.png" <<'EOF'
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
chunks, idat, pos = [], b"", 8
while pos < len(data):
    (length,) = struct.unpack(">I", data[pos:pos + 4])
    kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
    if kind == b"IDAT":
        if not idat:
            chunks.append((b"IDAT", None))  # where the image data goes
        idat += body
    else:
        chunks.append((kind, body))
    pos += 12 + length
deflated = zlib.compress(zlib.decompress(idat), 9)
with open(sys.argv[2], "wb") as out:
    out.write(data[:8])
    for kind, body in chunks:
        body = deflated if body is None else body
        out.write(struct.pack(">I", len(body)) + kind + body)
        out.write(struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))
EOF
done
ls -l "$root/docs/img/dem.png" "$root/docs/img/drift.png"
