"""Fails when a PNG is black: the mean of its bytes after inflating.

Usage: png_not_black.py IMAGE.png

Mean of the PNG's bytes after inflating (8-bit RGB rows with filter bytes):
enough to tell a black image from a lit one without an imaging library.
"""
import struct
import sys
import zlib

data = open(sys.argv[1], "rb").read()
chunks, i = [], 8
while i < len(data):
    n = struct.unpack(">I", data[i:i + 4])[0]
    if data[i + 4:i + 8] == b"IDAT":
        chunks.append(data[i + 8:i + 8 + n])
    i += 12 + n
raw = zlib.decompress(b"".join(chunks))
mean = sum(raw) / len(raw)
if mean < 8:
    print(f"{sys.argv[1]}: black (mean byte {mean:.1f})")
    sys.exit(1)
print(f"ok {sys.argv[1]}: mean byte {mean:.1f}")
