"""Wavefront OBJ meshes: `read_obj` into a `Mesh`, `write_obj` out of one.

The reader takes the geometry statements and ignores the rest (o, g, s,
usemtl, mtllib, l, p, comments):

    v x y z [w | r g b]     a position; only x y z are kept
    vt u [v [w]]            a texture coordinate; v defaults to 0
    vn x y z                a normal; normalised on reading
    f a b c ...             a polygon of 3 or more corners, each v, v/vt,
                            v//vn or v/vt/vn, fan-triangulated as
                            (0,1,2), (0,2,3), ...

Indices count from 1; a negative index counts back from the last element
defined above the face's line (-1 is the latest). The mesh gets
corner_normals when every corner names a vn and corner_uvs when every corner
names a vt. Every error names the file and, where there is one, the line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..scene import Mesh
from .files import write_whole

# Statements the reader stores: keyword -> (name in messages, plural, fewest numbers, numbers kept)
_ELEMENTS = {"v": ("vertex", "vertices", 3, 3), "vt": ("texture coordinate", "texture coordinates", 1, 2),
             "vn": ("normal", "normals", 3, 3)}


class ObjError(ValueError):
    """The file is not a usable OBJ mesh; the message names the file and line."""


class _Statements:
    """The tokens of one kind of statement, gathered line by line.

    lines   line number of each statement
    counts  number of tokens after the keyword in each statement
    tokens  all those tokens, concatenated
    """

    def __init__(self):
        self.lines: list[int] = []
        self.counts: list[int] = []
        self.tokens: list[str] = []

    def add(self, line: int, fields: list[str]) -> None:
        self.lines.append(line)
        self.counts.append(len(fields))
        self.tokens += fields


def read_obj(path) -> Mesh:
    """The triangle mesh in the OBJ file at `path`, in the file's coordinates."""
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise ObjError(f"{path}: cannot read the mesh file: {exc.strerror or exc}") from None
    return parse_obj(text, str(path))


def parse_obj(text: str, name: str = "<obj>") -> Mesh:
    """The triangle mesh in OBJ `text`; `name` is the file named in errors."""
    elements = {key: _Statements() for key in _ELEMENTS}
    faces = _Statements()
    before = []  # per face: (v, vt, vn) defined above its line
    for number, line in enumerate(text.splitlines(), 1):
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        if fields[0] in elements:
            elements[fields[0]].add(number, fields[1:])
        elif fields[0] == "f":
            faces.add(number, fields[1:])
            before.append([len(elements[key].lines) for key in _ELEMENTS])

    values = {key: _numbers(name, key, statements) for key, statements in elements.items()}
    if not faces.lines:
        raise ObjError(f"{name}: the file has no faces, so the mesh has no triangles")
    short = np.flatnonzero(np.array(faces.counts) < 3)
    if len(short):
        raise ObjError(f"{name}: line {faces.lines[short[0]]}: a face needs at least 3 corners")

    index, present, corner_line = _corner_indices(name, faces)
    corner_before = np.repeat(np.array(before), faces.counts, axis=0)  # (nc,3)
    resolved = {key: _resolve(name, key, index[:, k], present[:, k], corner_line, len(values[key]),
                              corner_before[:, k])
                for k, key in enumerate(_ELEMENTS)}  # each (nc,) 0-based
    corner = _fan(np.array(faces.counts))  # (nt,3) indices into the face corners

    normals = uvs = None
    if present[:, 2].all():
        normals = values["vn"][resolved["vn"][corner]]
    if present[:, 1].all():
        uvs = values["vt"][resolved["vt"][corner]]
    return Mesh(values["v"], resolved["v"][corner], normals, uvs)


def _numbers(name: str, key: str, statements: _Statements) -> np.ndarray:
    """(n, kept) float64 values of one kind of statement, with short, malformed
    and non-finite ones reported by line."""
    what, _, fewest, kept = _ELEMENTS[key]
    counts = np.array(statements.counts, dtype=np.int64)
    if len(counts) == 0:
        return np.zeros((0, kept))
    short = np.flatnonzero(counts < fewest)
    if len(short):
        raise ObjError(f"{name}: line {statements.lines[short[0]]}: '{key}' needs {fewest} numbers, "
                       f"got {counts[short[0]]}")
    starts = np.cumsum(counts) - counts
    tokens = np.array(statements.tokens + ["0"])
    pick = starts[:, None] + np.arange(kept)  # (n, kept) token indices; missing ones read the final "0"
    pick = np.where(np.arange(kept) < counts[:, None], pick, len(tokens) - 1)
    try:
        numbers = tokens[pick].astype(np.float64)
    except ValueError:
        row = next(i for i in range(len(pick)) if not _parses(tokens[pick[i]], float))
        raise ObjError(f"{name}: line {statements.lines[row]}: malformed {what} "
                       f"'{' '.join(tokens[pick[row]])}'") from None
    bad = np.flatnonzero(~np.isfinite(numbers).all(axis=1))
    if len(bad):
        raise ObjError(f"{name}: line {statements.lines[bad[0]]}: the {what} has NaN or infinite coordinates")
    if key == "vn":
        length = np.linalg.norm(numbers, axis=1)
        zero = np.flatnonzero(length == 0)
        if len(zero):
            raise ObjError(f"{name}: line {statements.lines[zero[0]]}: the normal has zero length")
        numbers /= length[:, None]
    return numbers


def _parses(tokens: np.ndarray, kind) -> bool:
    try:
        tokens.astype(kind)
    except ValueError:
        return False
    return True


def _corner_indices(name: str, faces: _Statements):
    """Each face corner's raw OBJ indices.

    Returns index (nc,3) int64 (v, vt, vn; 0 where absent), present (nc,3)
    bool, and the line number (nc,) of each corner's face."""
    corner_line = np.repeat(np.array(faces.lines), faces.counts)
    tokens = np.array(faces.tokens)
    slashes = np.char.count(tokens, "/")
    double = np.char.find(tokens, "//") >= 0
    malformed = np.flatnonzero((slashes > 2) | (double & (slashes != 2)))
    if len(malformed):
        i = malformed[0]
        raise ObjError(f"{name}: line {corner_line[i]}: malformed face corner '{tokens[i]}'")
    present = np.stack([np.ones(len(tokens), bool), (slashes >= 1) & ~double, slashes == 2], axis=1)
    padded = np.char.add(np.char.replace(tokens, "//", "/0/"), np.array(["/0/0", "/0", ""])[slashes])
    fields = np.array("/".join(padded.tolist()).split("/")).reshape(-1, 3)
    try:
        index = fields.astype(np.int64)
    except ValueError:
        row = next(i for i in range(len(fields)) if not _parses(fields[i], np.int64))
        raise ObjError(f"{name}: line {corner_line[row]}: malformed face corner '{tokens[row]}'") from None
    return index, present, corner_line


def _resolve(name: str, key: str, index: np.ndarray, present: np.ndarray, corner_line: np.ndarray, total: int,
             before: np.ndarray) -> np.ndarray:
    """0-based indices (nc,) of one element kind from OBJ indices `index (nc,)`;
    `before (nc,)` counts the elements defined above each corner's line."""
    resolved = np.where(index > 0, index - 1, before + index)
    bad = np.flatnonzero(present & ((index == 0) | (resolved < 0) | (resolved >= total)))
    if len(bad):
        i = bad[0]
        what, plural = _ELEMENTS[key][:2]
        known = f"the file has {total} {plural}" if index[i] > 0 else f"{before[i]} {plural} precede this line"
        raise ObjError(f"{name}: line {corner_line[i]}: {what} index {index[i]} is out of range: {known}")
    return resolved


def _fan(counts: np.ndarray) -> np.ndarray:
    """(nt,3) corner indices of the fan triangulation of polygons with
    `counts (nf,)` corners each, stored one after another."""
    per_face = counts - 2
    first = np.repeat(np.cumsum(counts) - counts, per_face)
    step = np.arange(per_face.sum()) - np.repeat(np.cumsum(per_face) - per_face, per_face) + 1
    return np.stack([first, first + step, first + step + 1], axis=1)


def _unique_rows(rows: np.ndarray, decimals: int) -> tuple[np.ndarray, np.ndarray]:
    """Distinct rows of `rows (n,k)` rounded to `decimals`, and each row's
    index (n,) into them."""
    rounded = np.round(rows, decimals) + 0.0  # + 0.0 turns -0.0 into 0.0
    unique, inverse = np.unique(rounded, axis=0, return_inverse=True)
    return unique, inverse.reshape(-1)


def write_obj(path, mesh: Mesh, comment: str = "", decimals: int = 6) -> None:
    """Write `mesh` as OBJ with `decimals` decimal places, sharing equal
    positions, normals and texture coordinates; vn and vt when the mesh has
    corner normals and UVs. Written whole (files.py)."""
    verts, v_index = _unique_rows(mesh.vertices, decimals)
    columns = [v_index[mesh.triangles] + 1]  # each (nt,3), 1-based
    lines = [f"# {line}" for line in comment.splitlines()]
    blocks = [("v", verts)]
    if mesh.corner_uvs is not None:
        uvs, vt_index = _unique_rows(mesh.corner_uvs.reshape(-1, 2), decimals)
        blocks.append(("vt", uvs))
        columns.append(vt_index.reshape(-1, 3) + 1)
    if mesh.corner_normals is not None:
        normals, vn_index = _unique_rows(mesh.corner_normals.reshape(-1, 3), decimals)
        blocks.append(("vn", normals))
        columns.append(vn_index.reshape(-1, 3) + 1)
    corner = {1: "%d", 2: "%d/%d", 3: "%d/%d/%d"}[len(columns)]
    if mesh.corner_normals is not None and mesh.corner_uvs is None:
        corner = "%d//%d"
    faces = np.stack(columns, axis=-1).reshape(len(mesh.triangles), -1)  # (nt, 3 * attributes)

    def write(temporary: str) -> None:
        with open(temporary, "w", encoding="utf-8") as out:
            out.write("".join(line + "\n" for line in lines))
            for keyword, rows in blocks:
                np.savetxt(out, rows, fmt=" ".join([keyword] + [f"%.{decimals}f"] * rows.shape[1]))
            np.savetxt(out, faces, fmt=" ".join(["f"] + [corner] * 3))

    write_whole(path, write, None)
