"""Renders to files with only the standard library and numpy (Blender's
Python has no Pillow): 8-bit sRGB PNG or float32 OpenEXR. The readers are
minimal: they read what the writers write, for round-trip tests.

Images are (h, w, 4) float32 linear RGBA with row 0 at the top, as
`RenderResult.image`.

PNG: the PNG specification (W3C, 2003), colour type 6 (RGBA, 8 bits), filter
type 0 on every row, with an sRGB chunk. Colour goes through the sRGB OETF of
IEC 61966-2-1, clipped to [0, 1]; alpha is stored linearly.

OpenEXR: "The OpenEXR File Layout" (openexr.com): a single-part scanline
file, uncompressed, one scanline per block, FLOAT channels stored in
alphabetical order (A, B, G, R); any named channels, for Blender's
multilayer files.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_EXR_MAGIC = 20000630
_EXR_FLOAT = 2
_EXR_DTYPES = {1: "<f2", 2: "<f4"}  # pixel type HALF, FLOAT


class ImageFormatError(ValueError):
    """The file name's extension names no format this module writes."""


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB OETF of linear values clipped to [0, 1]; NaN counts as 0."""
    x = np.clip(np.nan_to_num(linear, nan=0.0), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def write_png(path, rgba: np.ndarray) -> None:
    """8-bit sRGB RGBA PNG of linear `rgba (h,w,4)`."""
    h, w = rgba.shape[:2]
    levels = np.empty((h, w, 4), dtype=np.float64)
    levels[..., :3] = srgb_encode(rgba[..., :3])
    levels[..., 3] = np.clip(np.nan_to_num(rgba[..., 3], nan=0.0), 0.0, 1.0)
    rows = np.zeros((h, 1 + 4 * w), dtype=np.uint8)  # each row: filter type 0, then its bytes
    rows[:, 1:] = np.round(levels * 255.0).astype(np.uint8).reshape(h, 4 * w)
    header = struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)
    with open(path, "wb") as out:
        out.write(_PNG_SIGNATURE)
        out.write(_png_chunk(b"IHDR", header))
        out.write(_png_chunk(b"sRGB", b"\x00"))
        out.write(_png_chunk(b"IDAT", zlib.compress(rows.tobytes(), 6)))
        out.write(_png_chunk(b"IEND", b""))


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def read_png(path) -> np.ndarray:
    """(h,w,4) uint8 RGBA of an 8-bit RGBA PNG whose rows all use filter 0."""
    data = Path(path).read_bytes()
    if not data.startswith(_PNG_SIGNATURE):
        raise ValueError(f"{path}: not a PNG file")
    pos, idat, header = len(_PNG_SIGNATURE), [], None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])[0] != zlib.crc32(kind + body):
            raise ValueError(f"{path}: {kind.decode()} chunk fails its CRC")
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        pos += 12 + length
    w, h, depth, colour, _, _, interlace = header
    if (depth, colour, interlace) != (8, 6, 0):
        raise ValueError(f"{path}: only 8-bit RGBA, non-interlaced PNGs are read here")
    rows = np.frombuffer(zlib.decompress(b"".join(idat)), dtype=np.uint8).reshape(h, 1 + 4 * w)
    if rows[:, 0].any():
        raise ValueError(f"{path}: only filter type 0 is read here")
    return rows[:, 1:].reshape(h, w, 4).copy()


def write_exr(path, rgba: np.ndarray) -> None:
    """Uncompressed float32 RGBA OpenEXR of linear `rgba (h,w,4)`."""
    write_exr_channels(path, {name: rgba[..., "RGBA".index(name)] for name in "RGBA"})


def write_exr_channels(path, channels: dict[str, np.ndarray]) -> None:
    """Uncompressed float32 OpenEXR of named `channels`, each (h,w) with row
    0 at the top. Names with dots are Blender's multilayer convention,
    "<layer>.<pass>.<channel>" (e.g. "ViewLayer.Combined.R")."""
    names = sorted(channels)  # the layout stores channels in alphabetical order
    h, w = np.shape(channels[names[0]])
    chlist = b"".join(name.encode() + b"\0" + struct.pack("<iB3xii", _EXR_FLOAT, 0, 1, 1)
                      for name in names) + b"\0"
    window = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    header = b"".join([
        _exr_attribute("channels", "chlist", chlist),
        _exr_attribute("compression", "compression", b"\0"),
        _exr_attribute("dataWindow", "box2i", window),
        _exr_attribute("displayWindow", "box2i", window),
        _exr_attribute("lineOrder", "lineOrder", b"\0"),
        _exr_attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0)),
        _exr_attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)),
        _exr_attribute("screenWindowWidth", "float", struct.pack("<f", 1.0)),
    ]) + b"\0"
    # one block per scanline: y, byte count, then each channel's w values
    block = np.dtype([("y", "<i4"), ("size", "<i4"), ("pixels", "<f4", (len(names), w))])
    blocks = np.zeros(h, dtype=block)
    blocks["y"] = np.arange(h)
    blocks["size"] = 4 * len(names) * w
    blocks["pixels"] = np.stack([np.asarray(channels[name], dtype=np.float32) for name in names], axis=1)
    start = 8 + len(header) + 8 * h
    offsets = start + block.itemsize * np.arange(h, dtype="<u8")
    with open(path, "wb") as out:
        out.write(struct.pack("<ii", _EXR_MAGIC, 2))
        out.write(header)
        out.write(offsets.astype("<u8").tobytes())
        out.write(blocks.tobytes())


def _exr_attribute(name: str, kind: str, value: bytes) -> bytes:
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def read_exr(path) -> np.ndarray:
    """(h,w,4) float32 RGBA of an uncompressed single-part scanline OpenEXR
    with FLOAT or HALF channels; a missing A reads as 1."""
    data = Path(path).read_bytes()
    magic, version = struct.unpack("<ii", data[:8])
    if magic != _EXR_MAGIC or version & 0xFF != 2 or version & ~0xFF:
        raise ValueError(f"{path}: not a single-part scanline OpenEXR file")
    pos, attributes = 8, {}
    while data[pos] != 0:
        name_end = data.index(b"\0", pos)
        kind_end = data.index(b"\0", name_end + 1)
        (size,) = struct.unpack("<i", data[kind_end + 1:kind_end + 5])
        attributes[data[pos:name_end].decode()] = data[kind_end + 5:kind_end + 5 + size]
        pos = kind_end + 5 + size
    pos += 1
    if attributes["compression"] != b"\0":
        raise ValueError(f"{path}: only uncompressed OpenEXR files are read here")
    channels, chlist = [], attributes["channels"]
    while chlist[0] != 0:
        end = chlist.index(b"\0")
        channels.append((chlist[:end].decode(), struct.unpack("<i", chlist[end + 1:end + 5])[0]))
        chlist = chlist[end + 17:]
    if any(kind not in _EXR_DTYPES for _, kind in channels):
        raise ValueError(f"{path}: only HALF and FLOAT channels are read here")
    x0, y0, x1, y1 = struct.unpack("<iiii", attributes["dataWindow"])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    offsets = np.frombuffer(data, dtype="<u8", count=h, offset=pos)
    image = np.ones((h, w, 4), dtype=np.float32)
    for offset in offsets.tolist():
        y, _ = struct.unpack("<ii", data[offset:offset + 8])
        at = offset + 8
        for name, kind in channels:
            values = np.frombuffer(data, dtype=_EXR_DTYPES[kind], count=w, offset=at)
            at += values.nbytes
            if name in ("R", "G", "B", "A"):
                image[y - y0, :, "RGBA".index(name)] = values
    return image


WRITERS = {".png": write_png, ".exr": write_exr}


def check_format(path) -> None:
    """Raise ImageFormatError unless `path`'s extension is one `write_image` writes."""
    suffix = Path(path).suffix.lower()
    if suffix not in WRITERS:
        raise ImageFormatError(f"{path}: cannot write images of type '{suffix or '(no extension)'}': "
                               f"use {' or '.join(WRITERS)}")


def write_image(path, rgba: np.ndarray, exposure: float = 0.0) -> None:
    """Write linear `rgba (h,w,4)` to `path` (.png or .exr), its colour scaled
    by 2^exposure (exposure in stops, EV)."""
    check_format(path)
    image = np.array(rgba, dtype=np.float32)
    image[..., :3] *= np.float32(2.0 ** exposure)
    WRITERS[Path(path).suffix.lower()](path, image)
