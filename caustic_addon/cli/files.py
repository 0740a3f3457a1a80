"""Files written whole: every file the command line and the add-on write
goes to a temporary file beside its final name, is synced to the disk,
checked complete by its format's own structure, and only then renamed
over the final name. A write that fails (a full disk, a writer that stops
short without saying so, as Blender's PNG, WebP and Targa writers do)
leaves no file behind and the earlier file whole, and says why.

The checks read what each format records of its own length, not the
pixels: PNG's chunks with their CRCs up to IEND; JPEG's and JPEG 2000's
end-of-image marker; the box sizes of JPEG 2000 and AVIF (ISO BMFF);
RIFF's size (WebP); the file size that BMP, Cineon and DPX headers hold;
an SGI (Iris) file's size or its RLE tables; Targa's footer; TIFF's strip
or tile table; a Radiance HDR's run-length scanlines; and an OpenEXR
file's offset table, each chunk inside the file and the last ending it.
"""

from __future__ import annotations

import errno
import mmap
import os
import shutil
import struct
import uuid
import zlib
from typing import Callable

import numpy as np

from ..util.jit import kernel

# Blender's names of the image formats (ImageFormatSettings.file_format) as users read them.
FORMAT_NAMES = {"PNG": "PNG", "JPEG": "JPEG", "JPEG2000": "JPEG 2000", "OPEN_EXR": "OpenEXR",
                "OPEN_EXR_MULTILAYER": "OpenEXR", "TIFF": "TIFF", "BMP": "BMP", "TARGA": "Targa",
                "TARGA_RAW": "Targa", "IRIS": "Iris", "HDR": "Radiance HDR", "CINEON": "Cineon", "DPX": "DPX",
                "WEBP": "WebP", "AVIF": "AVIF"}
# OpenEXR's compression codes -> scanlines per chunk ("The OpenEXR File Layout"; HTJ2K: OpenEXR 3.4)
_EXR_LINES = {0: 1, 1: 1, 2: 1, 3: 16, 4: 32, 5: 16, 6: 32, 7: 32, 8: 32, 9: 256, 10: 256, 11: 32}
_TARGA_FOOTER = b"TRUEVISION-XFILE.\0"


class IncompleteFile(ValueError):
    """A file is not whole, or not of the format asked for; the message says how."""


class WriteError(Exception):
    """A file could not be written whole; the earlier file at its path, if any, is as it was."""

    def __init__(self, path, reason: str):
        super().__init__(f"could not write '{os.fspath(path)}': {reason}")
        self.path, self.reason = os.fspath(path), reason


def write_whole(path, write: Callable[[str], None], file_format: str | None) -> None:
    """`write(temporary path)` writes the file in `file_format` (one of
    FORMAT_NAMES, or None for a text file Python writes, whose every failed
    write raises); it is synced, checked whole, and renamed to `path`.
    Raises WriteError, with the temporary file removed, if `write` raises
    OSError or the file is not whole; anything else `write` raises (a bug,
    Ctrl-C) comes out as it is, with the temporary file removed too."""
    path = os.path.abspath(os.fspath(path))
    folder, name = os.path.split(path)
    temporary = os.path.join(folder, f".{name}.{uuid.uuid4().hex[:8]}.part")
    try:
        write(temporary)
        if not os.path.isfile(temporary):
            raise IncompleteFile("nothing was written")
        _sync(temporary)
        if file_format is not None:
            check_whole(temporary, file_format)
        os.replace(temporary, path)
    except OSError as exc:
        reason = exc.strerror or str(exc)
        raise WriteError(path, reason if exc.errno == errno.ENOSPC else reason + _full_disk(folder)) from exc
    except IncompleteFile as exc:
        raise WriteError(path, f"{exc}{_full_disk(folder)}") from exc
    finally:
        if os.path.lexists(temporary):
            try:
                os.remove(temporary)
            except OSError:
                pass
    _sync_folder(folder)


def _sync(path: str) -> None:
    """The file's data on the disk: a write the disk could not take shows here, where it shows at all."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _sync_folder(folder: str) -> None:
    """The rename on the disk too (POSIX; Windows cannot open a folder, and needs no such step)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _full_disk(folder: str) -> str:
    """What to add to a reason where the folder's disk is (nearly) full."""
    try:
        free = shutil.disk_usage(folder).free
    except OSError:
        return ""
    return f"; its disk is full ({free:,} bytes free): free some space" if free < 1 << 20 else ""


def check_whole(path, file_format: str) -> None:
    """Raise IncompleteFile unless the file at `path` is a whole file of
    `file_format` (one of FORMAT_NAMES) by its own structure."""
    name = FORMAT_NAMES.get(file_format)
    if name is None:
        raise IncompleteFile(f"the add-on cannot check that a {file_format} file is whole: choose another format")
    size = os.path.getsize(path)
    if size == 0:
        raise IncompleteFile(f"the {name} file written is empty")
    with open(path, "rb") as handle, mmap.mmap(handle.fileno(), 0, access=mmap.ACCESS_COPY) as data:
        try:
            problem = _CHECKS[file_format](data)
        except (struct.error, IndexError, ValueError) as exc:
            problem = f"its structure cannot be read ({exc})"
    if problem:
        raise IncompleteFile(f"the {name} file written is not whole: {problem} ({size:,} bytes)")


def _png(data) -> str | None:
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        return "it is not a PNG file"
    pos, kind, view = 8, b"", memoryview(data)
    try:
        while pos + 12 <= len(data) and kind != b"IEND":
            length, kind = struct.unpack(">I4s", data[pos:pos + 8])
            if pos + 12 + length > len(data):
                return f"its {kind.decode(errors='replace')} chunk runs past the end"
            (crc,) = struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])
            if zlib.crc32(view[pos + 4:pos + 8 + length]) != crc:
                return f"its {kind.decode(errors='replace')} chunk fails its CRC"
            pos += 12 + length
    finally:
        view.release()
    if kind != b"IEND":
        return "it stops before its IEND chunk"
    return None if pos == len(data) else "it goes on past its IEND chunk"


def _jpeg(data) -> str | None:
    if data[:2] != b"\xff\xd8":
        return "it is not a JPEG file"
    return None if data[-2:] == b"\xff\xd9" else "it stops before its end-of-image marker"


def _boxes(data, start: int = 0) -> tuple[list[bytes], str | None]:
    """The kinds of the ISO BMFF boxes from `start` to the end, and what is wrong with them, if anything."""
    kinds, pos = [], start
    while pos < len(data):
        if pos + 8 > len(data):
            return kinds, "it stops inside a box's header"
        size, kind = struct.unpack(">I4s", data[pos:pos + 8])
        if size == 1:
            (size,) = struct.unpack(">Q", data[pos + 8:pos + 16])
        elif size == 0:
            size = len(data) - pos
        if size < 8 or pos + size > len(data):
            return kinds, f"its '{kind.decode(errors='replace')}' box runs past the end"
        kinds.append(kind)
        pos += size
    return kinds, None


def _jpeg2000(data) -> str | None:
    if data[:4] == b"\xff\x4f\xff\x51":  # a bare codestream
        return None if data[-2:] == b"\xff\xd9" else "it stops before its end-of-codestream marker"
    if data[4:8] != b"jP  ":
        return "it is not a JPEG 2000 file"
    kinds, problem = _boxes(data)
    if problem:
        return problem
    if b"jp2c" not in kinds:
        return "it has no codestream"
    return None if data[-2:] == b"\xff\xd9" else "it stops before its end-of-codestream marker"


def _avif(data) -> str | None:
    if data[4:8] != b"ftyp":
        return "it is not an AVIF file"
    kinds, problem = _boxes(data)
    return problem or (None if b"mdat" in kinds else "it has no image data ('mdat' box)")


def _webp(data) -> str | None:
    if data[:4] != b"RIFF" or data[8:12] != b"WEBP":
        return "it is not a WebP file"
    (size,) = struct.unpack("<I", data[4:8])
    return None if len(data) in (8 + size, 8 + size + (size & 1)) else f"its RIFF header says {8 + size:,} bytes"


def _bmp(data) -> str | None:
    if data[:2] != b"BM":
        return "it is not a BMP file"
    (size,) = struct.unpack("<I", data[2:6])
    return None if size == len(data) else f"its header says {size:,} bytes"


def _cineon(data) -> str | None:
    order = {b"\x80\x2a\x5f\xd7": ">", b"\xd7\x5f\x2a\x80": "<"}.get(bytes(data[:4]))
    if order is None:
        return "it is not a Cineon file"
    (size,) = struct.unpack(order + "I", data[20:24])
    return None if size == len(data) else f"its header says {size:,} bytes"


def _dpx(data) -> str | None:
    order = {b"SDPX": ">", b"XPDS": "<"}.get(bytes(data[:4]))
    if order is None:
        return "it is not a DPX file"
    (size,) = struct.unpack(order + "I", data[16:20])
    return None if size == len(data) else f"its header says {size:,} bytes"


def _iris(data) -> str | None:
    magic, storage, bpc, _, w, h, channels = struct.unpack(">hBBHHHH", data[:12])
    if magic != 474:
        return "it is not an Iris (SGI) file"
    if storage == 0:
        size = 512 + w * h * channels * bpc
        return None if size == len(data) else f"its header says {size:,} bytes"
    rows = h * channels
    starts = np.frombuffer(data, dtype=">u4", count=rows, offset=512).astype(np.int64)
    lengths = np.frombuffer(data, dtype=">u4", count=rows, offset=512 + 4 * rows).astype(np.int64)
    ends = starts + lengths
    if np.any(starts < 512 + 8 * rows) or np.any(lengths == 0) or ends.max() > len(data):
        return "its run-length tables point past the end"
    return None if ends.max() == len(data) else "it goes on past its last row"


def _targa(data) -> str | None:
    if data[-len(_TARGA_FOOTER):] != _TARGA_FOOTER:
        return "it stops before its footer"
    extension, developer = struct.unpack("<II", data[-26:-18])
    return None if max(extension, developer) < len(data) - 26 else "its footer points past the end"


def _tiff(data) -> str | None:
    order = {b"II*\0": "<", b"MM\0*": ">"}.get(bytes(data[:4]))
    if order is None:
        return "it is not a TIFF file"
    (ifd,) = struct.unpack(order + "I", data[4:8])
    if ifd < 8 or ifd + 2 > len(data):
        return "its directory is missing"
    (count,) = struct.unpack(order + "H", data[ifd:ifd + 2])
    if ifd + 2 + 12 * count + 4 > len(data):
        return "its directory runs past the end"
    tags = {}
    for entry in range(ifd + 2, ifd + 2 + 12 * count, 12):
        tag, kind, n = struct.unpack(order + "HHI", data[entry:entry + 8])
        width = {1: 1, 2: 1, 3: 2, 4: 4, 5: 8, 6: 1, 7: 1, 8: 2, 9: 4, 10: 8, 11: 4, 12: 8}.get(kind, 1)
        at = entry + 8
        if width * n > 4:
            (at,) = struct.unpack(order + "I", data[entry + 8:entry + 12])
            if at + width * n > len(data):
                return f"its tag {tag}'s values lie past the end"
        if tag in (273, 279, 324, 325) and kind in (3, 4):
            tags[tag] = np.frombuffer(data, dtype=order + ("u2" if kind == 3 else "u4"), count=n,
                                      offset=at).astype(np.int64)
    offsets, counts = (tags.get(273), tags.get(279)) if 273 in tags else (tags.get(324), tags.get(325))
    if offsets is None or counts is None or len(offsets) != len(counts):
        return "it has no table of its image data"
    if np.any(counts == 0) or (offsets + counts).max() > len(data):
        return "its image data stops short"
    return None


def _hdr(data) -> str | None:
    if data[:2] != b"#?":
        return "it is not a Radiance HDR file"
    header_end = data.find(b"\n\n")
    line_end = data.find(b"\n", header_end + 2)
    if header_end < 0 or line_end < 0:
        return "it stops inside its header"
    words = bytes(data[header_end + 2:line_end]).split()
    if len(words) != 4 or words[0][1:] not in (b"Y", b"X") or words[2][1:] not in (b"Y", b"X"):
        return "its resolution line cannot be read"
    lines, width = int(words[1]), int(words[3])
    end = _hdr_scanlines_end(np.frombuffer(data, dtype=np.uint8), line_end + 1, width, lines)
    if end < 0:
        return "it stops inside its scanlines"
    return None if end == len(data) else "it goes on past its last scanline"


@kernel("i8(u1[::1], i8, i8, i8)")
def _hdr_scanlines_end(data, pos, width, lines):
    """Where `lines` scanlines of `width` RGBE pixels from `pos` end, or -1
    if they run past the end of `data`: each is flat (4 bytes a pixel) or,
    from 2 2 and its width, four channels of runs (a count over 128 repeats
    the next byte, else that many bytes follow) (Radiance's color.c)."""
    n = len(data)
    for _ in range(lines):
        if pos + 4 > n:
            return -1
        rle = (8 <= width < 32768 and data[pos] == 2 and data[pos + 1] == 2
               and (np.int64(data[pos + 2]) << 8 | data[pos + 3]) == width)
        if not rle:
            pos += 4 * width
            continue
        pos += 4
        for _channel in range(4):
            filled = 0
            while filled < width:
                if pos >= n:
                    return -1
                count = np.int64(data[pos])
                if count == 0 or count == 128:
                    return -1
                if count > 128:
                    filled += count - 128
                    pos += 2
                else:
                    filled += count
                    pos += 1 + count
    return pos if pos <= n else -1


def _exr(data) -> str | None:
    magic, version = struct.unpack("<ii", data[:8])
    if magic != 20000630:
        return "it is not an OpenEXR file"
    if version & 0x1A00:  # tiled, deep or multi-part
        return "it is a tiled, deep or multi-part OpenEXR file, which cannot be checked"
    pos, attributes = 8, {}
    while data[pos] != 0:
        name_end = data.find(b"\0", pos)
        kind_end = data.find(b"\0", name_end + 1)
        if name_end < 0 or kind_end < 0:
            return "it stops inside its header"
        (size,) = struct.unpack("<i", data[kind_end + 1:kind_end + 5])
        attributes[bytes(data[pos:name_end])] = bytes(data[kind_end + 5:kind_end + 5 + size])
        pos = kind_end + 5 + size
    table = pos + 1
    _, y0, _, y1 = struct.unpack("<iiii", attributes[b"dataWindow"])
    rows = y1 - y0 + 1
    compression = attributes[b"compression"][0]
    if compression in _EXR_LINES:
        chunks = -(-rows // _EXR_LINES[compression])
    else:  # written in increasing y, the first chunk follows the table
        chunks = (struct.unpack("<Q", data[table:table + 8])[0] - table) // 8
    if table + 8 * chunks > len(data):
        return "it stops inside its offset table"
    offsets = np.frombuffer(data, dtype="<u8", count=chunks, offset=table).astype(np.int64)
    if np.any(offsets < table + 8 * chunks) or np.any(offsets + 8 > len(data)):
        return "its offset table points past the end"
    heads = np.frombuffer(data, dtype=np.uint8)[offsets[:, None] + np.arange(8)].copy().view("<i4")
    ends = offsets + 8 + heads[:, 1].astype(np.int64)
    if np.any(heads[:, 1] <= 0) or ends.max() > len(data):
        return "its last chunks stop short"
    if np.any((heads[:, 0] < y0) | (heads[:, 0] > y1)):
        return "a chunk's scanline lies outside the image"
    return None if ends.max() == len(data) else "it goes on past its last chunk"


_CHECKS = {"PNG": _png, "JPEG": _jpeg, "JPEG2000": _jpeg2000, "OPEN_EXR": _exr, "OPEN_EXR_MULTILAYER": _exr,
           "TIFF": _tiff, "BMP": _bmp, "TARGA": _targa, "TARGA_RAW": _targa, "IRIS": _iris, "HDR": _hdr,
           "CINEON": _cineon, "DPX": _dpx, "WEBP": _webp, "AVIF": _avif}
