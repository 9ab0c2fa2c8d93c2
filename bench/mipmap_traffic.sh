#!/usr/bin/env bash
# What mipmaps save the modelled chip: a generated floor under a 512² one-pixel-check
# texture running to the horizon (the downloaded scenes are used without their textures), cast
# by `raypipe simulate` (default configuration) from a built image, then from the same
# image with every texture cut down to level 0 (levels = 1, checksum resealed). Prints the
# cycles, the shading cache's hit rate and the shading bytes of each.
# Usage: bench/mipmap_traffic.sh [WxH]   (default 256x192)
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-256x192}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cargo build --release -q -p raypipe
R=$PWD/target/release/raypipe
python3 - "$tmp" <<'PY'
import struct, sys, zlib
d = sys.argv[1]
w = h = 512
raw = b''.join(b'\0' + b''.join(bytes([255 if ((x // 2) + (y // 2)) % 2 == 0 else 0] * 3) for x in range(w)) for y in range(h))
def chunk(t, data):
    return struct.pack('>I', len(data)) + t + data + struct.pack('>I', zlib.crc32(t + data) & 0xffffffff)
open(f'{d}/checker.png', 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0))
                                     + chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b''))
open(f'{d}/floor.mtl', 'w').write('newmtl checker\nKd 1 1 1\nmap_Kd checker.png\n')
open(f'{d}/floor.obj', 'w').write('mtllib floor.mtl\nv -20 0 -40\nv 20 0 -40\nv 20 0 2\nv -20 0 2\n'
                                  'vt -4 -8\nvt 4 -8\nvt 4 0.4\nvt -4 0.4\nvn 0 1 0\nusemtl checker\n'
                                  'f 1/1/1 3/3/1 2/2/1\nf 1/1/1 4/4/1 3/3/1\n')
open(f'{d}/floor.camera', 'w').write('eye 0 1 3\nlook_at 0 0.4 -10\nup 0 1 0\nfov 50\n')
PY
"$R" build "$tmp/floor.obj" --camera "$tmp/floor.camera" -o "$tmp/mipmapped.rpsi" >/dev/null 2>&1
python3 - "$tmp/mipmapped.rpsi" "$tmp/level0.rpsi" <<'PY'
import struct, sys, zlib
b = bytearray(open(sys.argv[1], 'rb').read())
for i in range(struct.unpack_from('<I', b, 20)[0]):
    kind, off, size, count = struct.unpack_from('<IIII', b, 64 + 16 * i)
    if kind == 15:  # TEXTURES: `levels` is the fifth word of each 32-byte record
        for r in range(count):
            struct.pack_into('<I', b, off + 32 * r + 16, 1)
struct.pack_into('<I', b, 28, 0)
struct.pack_into('<I', b, 28, zlib.crc32(bytes(b)) & 0xffffffff)
open(sys.argv[2], 'wb').write(b)
PY
for image in level0 mipmapped; do
  echo "== $image"
  "$R" simulate "$tmp/$image.rpsi" --camera "$tmp/floor.camera" --size "$size" -o "$tmp/$image.png" 2>&1 |
    grep -E "^frame|^cache shading|^memory"
done
