"""Renders to files with only the standard library and numpy (Blender's
Python has no Pillow): 8-bit sRGB PNG or float32 OpenEXR. The readers are
minimal: they read what the writers write, for round-trip tests.

Images are (h, w, 4) float32 linear RGBA with row 0 at the top, as
`RenderResult.image`.

PNG: the PNG specification (W3C, 2003), colour type 6 (RGBA, 8 bits), filter
type 0 on every row, with an sRGB chunk. Colour goes through the sRGB OETF of
IEC 61966-2-1, clipped to [0, 1]; alpha is stored linearly.

OpenEXR: "The OpenEXR File Layout" (openexr.com): a single-part scanline
file, FLOAT channels stored in alphabetical order (A, B, G, R); any named
channels, for Blender's multilayer files. ZIP compression, as Blender
writes by default: blocks of 16 scanlines, their bytes split into the
even and the odd ones, each byte then stored as its difference from the
one before plus 128, and deflated with zlib (OpenEXR's ImfZip.cpp); a
block that would not shrink is stored as it is. The reader also reads
uncompressed and ZIPS (one scanline a block) files.

Every file is written whole (files.py): a full disk leaves the earlier
file as it was.
"""

from __future__ import annotations

import math
import os
import struct
import zlib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from .files import write_whole

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_EXR_MAGIC = 20000630
_EXR_FLOAT = 2
_EXR_DTYPES = {1: "<f2", 2: "<f4"}  # pixel type HALF, FLOAT
_EXR_NONE, _EXR_ZIPS, _EXR_ZIP = 0, 2, 3  # compression
_EXR_BLOCK_LINES = {_EXR_NONE: 1, _EXR_ZIPS: 1, _EXR_ZIP: 16}
_ZIP_LEVEL = 4  # OpenEXR's default zlib level
_BLOCKS_IN_FLIGHT = 64
_FLOAT32_MAX = float(np.finfo(np.float32).max)
_LOG2_FLOAT32_MAX = math.log2(_FLOAT32_MAX) - 1e-6  # with room for float32's rounding of the scale


class ImageFormatError(ValueError):
    """The image cannot be written as asked: the file name's extension names
    no format this module writes, or the exposure takes it past float32."""


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB OETF of linear values clipped to [0, 1]; NaN counts as 0."""
    x = np.clip(np.nan_to_num(linear, nan=0.0), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def write_png(path, rgba: np.ndarray) -> None:
    """8-bit sRGB RGBA PNG of linear `rgba (h,w,4)`, written whole."""
    write_whole(path, lambda temporary: _png_file(temporary, rgba), "PNG")


def _png_file(path, rgba: np.ndarray) -> None:
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
    """ZIP-compressed float32 RGBA OpenEXR of linear `rgba (h,w,4)`, written whole."""
    write_exr_channels(path, {name: rgba[..., "RGBA".index(name)] for name in "RGBA"})


def write_exr_channels(path, channels: dict[str, np.ndarray]) -> None:
    """ZIP-compressed float32 OpenEXR of named `channels`, each (h,w) with
    row 0 at the top, written whole. Names with dots are Blender's
    multilayer convention, "<layer>.<pass>.<channel>" (e.g.
    "ViewLayer.Combined.R")."""
    write_whole(path, lambda temporary: _exr_file(temporary, channels), "OPEN_EXR")


def _exr_file(path, channels: dict[str, np.ndarray]) -> None:
    names = sorted(channels)  # the layout stores channels in alphabetical order
    h, w = np.shape(channels[names[0]])
    chlist = b"".join(name.encode() + b"\0" + struct.pack("<iB3xii", _EXR_FLOAT, 0, 1, 1)
                      for name in names) + b"\0"
    window = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    header = b"".join([
        _exr_attribute("channels", "chlist", chlist),
        _exr_attribute("compression", "compression", bytes([_EXR_ZIP])),
        _exr_attribute("dataWindow", "box2i", window),
        _exr_attribute("displayWindow", "box2i", window),
        _exr_attribute("lineOrder", "lineOrder", b"\0"),
        _exr_attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0)),
        _exr_attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)),
        _exr_attribute("screenWindowWidth", "float", struct.pack("<f", 1.0)),
    ]) + b"\0"
    lines = _EXR_BLOCK_LINES[_EXR_ZIP]
    starts = range(0, h, lines)
    table = 8 + len(header)
    offsets = np.zeros(len(starts), dtype="<u8")
    at = table + offsets.nbytes

    def block(y: int) -> bytes:
        """Scanlines y.. of the block: each channel's w values in turn, line by line, packed."""
        raw = np.stack([np.asarray(channels[name][y:y + lines], dtype="<f4") for name in names], axis=1)
        return _zip_pack(raw.tobytes())

    with open(path, "wb") as out, ThreadPoolExecutor(os.cpu_count() or 1) as pool:
        out.write(struct.pack("<ii", _EXR_MAGIC, 2))
        out.write(header)
        out.write(offsets.tobytes())  # filled in once the blocks are written
        for first in range(0, len(starts), _BLOCKS_IN_FLIGHT):  # zlib lets go of the GIL as it deflates
            batch = starts[first:first + _BLOCKS_IN_FLIGHT]
            for index, (y, packed) in enumerate(zip(batch, pool.map(block, batch)), start=first):
                offsets[index] = at
                out.write(struct.pack("<ii", y, len(packed)))
                out.write(packed)
                at += 8 + len(packed)
        out.seek(table)
        out.write(offsets.tobytes())


def _zip_pack(raw: bytes) -> bytes:
    """A block's bytes as OpenEXR's ZIP stores them, or as they are if that is no smaller."""
    data = np.frombuffer(raw, dtype=np.uint8)
    split = np.concatenate([data[0::2], data[1::2]])
    split[1:] = np.diff(split) + np.uint8(128)  # uint8 wraps around as the C code's does
    packed = zlib.compress(split.tobytes(), _ZIP_LEVEL)
    return packed if len(packed) < len(raw) else raw


def _zip_unpack(packed: bytes, size: int) -> bytes:
    """The `size` bytes of a block OpenEXR's ZIP packed."""
    if len(packed) >= size:
        return packed
    split = np.frombuffer(zlib.decompress(packed), dtype=np.uint8).astype(np.int64)
    split[1:] -= 128
    split = (np.cumsum(split) & 255).astype(np.uint8)
    data = np.empty_like(split)
    half = (len(split) + 1) // 2
    data[0::2], data[1::2] = split[:half], split[half:]
    return data.tobytes()


def _exr_attribute(name: str, kind: str, value: bytes) -> bytes:
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def read_exr(path) -> np.ndarray:
    """(h,w,4) float32 RGBA of a single-part scanline OpenEXR (read_exr_channels); a missing A reads as 1."""
    channels = read_exr_channels(path)
    h, w = next(iter(channels.values())).shape
    image = np.ones((h, w, 4), dtype=np.float32)
    for index, name in enumerate("RGBA"):
        if name in channels:
            image[..., index] = channels[name]
    return image


def read_exr_channels(path) -> dict[str, np.ndarray]:
    """Channel name -> (h,w) float32, row 0 at the top, of a single-part
    scanline OpenEXR with HALF or FLOAT channels, uncompressed, ZIPS or ZIP."""
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
    compression = attributes["compression"][0]
    if compression not in _EXR_BLOCK_LINES:
        raise ValueError(f"{path}: only uncompressed, ZIPS and ZIP OpenEXR files are read here")
    names, kinds, chlist = [], [], attributes["channels"]
    while chlist[0] != 0:
        end = chlist.index(b"\0")
        names.append(chlist[:end].decode())
        kinds.append(np.dtype(_EXR_DTYPES.get(struct.unpack("<i", chlist[end + 1:end + 5])[0], "V0")))
        chlist = chlist[end + 17:]
    if any(kind.itemsize == 0 for kind in kinds):
        raise ValueError(f"{path}: only HALF and FLOAT channels are read here")
    x0, y0, x1, y1 = struct.unpack("<iiii", attributes["dataWindow"])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    lines = _EXR_BLOCK_LINES[compression]
    line = np.dtype([(str(index), kind, (w,)) for index, kind in enumerate(kinds)])
    channels = {name: np.empty((h, w), dtype=np.float32) for name in names}
    for offset in np.frombuffer(data, dtype="<u8", count=-(-h // lines), offset=pos).tolist():
        y, size = struct.unpack("<ii", data[offset:offset + 8])
        rows = min(lines, y1 - y + 1)
        block = data[offset + 8:offset + 8 + size]
        if compression != _EXR_NONE:
            block = _zip_unpack(block, rows * line.itemsize)
        values = np.frombuffer(block, dtype=line, count=rows)
        for index, name in enumerate(names):
            channels[name][y - y0:y - y0 + rows] = values[str(index)]
    return channels


WRITERS = {".png": write_png, ".exr": write_exr}


def check_format(path) -> None:
    """Raise ImageFormatError unless `path`'s extension is one `write_image` writes."""
    suffix = Path(path).suffix.lower()
    if suffix not in WRITERS:
        raise ImageFormatError(f"{path}: cannot write images of type '{suffix or '(no extension)'}': "
                               f"use {' or '.join(WRITERS)}")


def write_image(path, rgba: np.ndarray, exposure: float = 0.0) -> None:
    """Write linear `rgba (h,w,4)` to `path` (.png or .exr), its colour scaled
    by 2^exposure (exposure in stops, EV). ImageFormatError where that would
    take a colour in an EXR past float32's largest value."""
    check_format(path)
    suffix = Path(path).suffix.lower()
    image = np.array(rgba, dtype=np.float64)
    brightest = float(np.abs(image[..., :3]).max(initial=0.0))
    if suffix == ".exr" and brightest > 0 and math.log2(brightest) + exposure >= _LOG2_FLOAT32_MAX:
        raise ImageFormatError(f"an exposure of {exposure:g} would make the brightest value 2^"
                               f"{math.log2(brightest) + exposure:.1f}, past the largest a float32 EXR holds "
                               f"({_FLOAT32_MAX:.3g}): use an exposure of "
                               f"{math.floor(_LOG2_FLOAT32_MAX - math.log2(brightest)):g} or less")
    # a PNG clips colour to 1: a larger scale than 2^150 lights nothing more, and would overflow
    image[..., :3] *= 2.0 ** (min(exposure, 150.0) if suffix == ".png" else exposure)
    WRITERS[suffix](path, image if suffix == ".png" else image.astype(np.float32))
