"""Joining bricks' mesh pieces (keys, V, F) into one mesh: vertices with equal keys become one, in
ascending key order; triangles follow in brick order, or where the pieces carry their triangles'
names (keys, V, F, names: GCP's local reconstruction) in name order, as the core joins its bricks
(in memory, the core's join itself). Either in memory, or streamed into a binary PLY whose join
holds only the keys (8 bytes per vertex of a piece, 8 per vertex kept) and the names' order (16
bytes per triangle) in memory, the pieces' vertices and triangles staying on disk. Keys are uint64
(marching cubes) or pairs of uint64 (the local reconstruction's), compared as pairs."""
import os
import shutil
import tempfile

import numpy as np

from . import _sdfcontour

_FACE = np.dtype([("n", "u1"), ("v", "<i4", (3,))])  # PLY's "list uchar int", 13 bytes
_CHUNK = 1 << 20


def _ply_header(vertices, triangles):
    return (f"ply\nformat binary_little_endian 1.0\ncomment written by sdfcontour\n"
            f"element vertex {vertices}\nproperty double x\nproperty double y\n"
            f"property double z\nelement face {triangles}\n"
            f"property list uchar int vertex_indices\nend_header\n").encode("ascii")


def _require_int32(vertices):
    if vertices > 2**31 - 1:
        raise ValueError(f"the mesh has {vertices} vertices: PLY's and the library's int32 "
                         f"indices hold at most 2147483647")


def _check_same_positions(V, kept, inverse):
    """Every copy of a vertex must sit where the kept copy does (the pieces' contract)."""
    for start in range(0, len(inverse), _CHUNK):
        part = slice(start, start + _CHUNK)
        if not np.array_equal(V[part], V[kept[inverse[part]]]):
            raise RuntimeError("internal error: two bricks place one vertex differently")


_PAIR = np.dtype([("hi", "<u8"), ("lo", "<u8")])


def _comparable(keys):
    """Keys as one sortable column: uint64 (marching cubes' edge keys) as they are, (v, 2) uint64
    pairs (the local reconstruction's) as records compared pair-wise."""
    keys = np.asarray(keys, np.uint64)
    if keys.ndim == 2:
        return np.ascontiguousarray(keys.astype("<u8", copy=False)).view(_PAIR).reshape(-1)
    return keys


def join_pieces(arrivals, count):
    """(V, F, stats) from `arrivals`, pairs (brick number < count, (keys, V, F[, names])): the
    core's join (join_local_pieces for named pieces, join_mesh_pieces for marching cubes')."""
    pieces = [None] * count
    for b, piece in arrivals:
        pieces[b] = piece
    empty = sum(len(p[2]) == 0 for p in pieces)
    if pieces and len(pieces[0]) == 4:
        V, F = _sdfcontour.join_local_pieces(pieces)
    else:
        V, F = _sdfcontour.join_mesh_pieces(pieces)
    return V, F, {"vertices": len(V), "triangles": len(F), "empty_bricks": empty}


def write_pieces_as_ply(arrivals, count, out):
    """Streams the joined mesh of `arrivals` into the binary PLY `out` (atomically: a failure
    leaves no file); returns the stats."""
    folder = tempfile.mkdtemp(prefix=".sdfcontour-join-", dir=os.path.dirname(os.path.abspath(out)))
    try:
        names = {n: os.path.join(folder, n)
                 for n in ("keys", "vertices", "faces", "names", "mesh.ply")}
        rows = [None] * count  # brick number -> (first face row, face rows)
        occurrences = face_rows = empty = 0
        key_type = None
        named = False
        with open(names["keys"], "wb") as kf, open(names["vertices"], "wb") as vf, \
                open(names["faces"], "wb") as ff, open(names["names"], "wb") as nf:
            for b, (keys, V, F, *named_triangles) in arrivals:
                if named_triangles:
                    named = True
                    np.asarray(named_triangles[0], np.uint64).tofile(nf)
                keys = _comparable(keys)
                if len(keys):
                    key_type = keys.dtype
                keys.tofile(kf)
                np.asarray(V, np.float64).tofile(vf)
                (np.asarray(F, np.int64) + occurrences).tofile(ff)
                rows[b] = (face_rows, len(F))
                occurrences += len(keys)
                face_rows += len(F)
                empty += len(F) == 0
        keys = np.fromfile(names["keys"], key_type or np.uint64)
        _, kept, inverse = np.unique(keys, return_index=True, return_inverse=True)
        del keys
        _require_int32(len(kept))
        V = np.memmap(names["vertices"], np.float64, "r", shape=(occurrences, 3)) \
            if occurrences else np.zeros((0, 3))
        _check_same_positions(V, kept, inverse)
        F = np.memmap(names["faces"], np.int64, "r", shape=(face_rows, 3)) \
            if face_rows else np.zeros((0, 3), np.int64)
        # Triangles in name order (the names as the pieces arrived, with their faces), or in
        # brick order, whatever order the bricks finished in.
        order = None
        if named and face_rows:
            order = np.argsort(np.fromfile(names["names"], np.uint64), kind="stable")
        spans = [(0, face_rows)] if order is not None else rows
        with open(names["mesh.ply"], "wb") as mesh:
            mesh.write(_ply_header(len(kept), face_rows))
            for start in range(0, len(kept), _CHUNK):
                np.ascontiguousarray(V[kept[start:start + _CHUNK]]).tofile(mesh)
            for first, size in spans:
                for start in range(first, first + size, _CHUNK):
                    end = min(start + _CHUNK, first + size)
                    part = F[order[start:end]] if order is not None else F[start:end]
                    faces = np.empty(len(part), _FACE)
                    faces["n"] = 3
                    faces["v"] = inverse[part]
                    faces.tofile(mesh)
        del V, F
        if face_rows:
            os.replace(names["mesh.ply"], out)
        return {"vertices": len(kept), "triangles": face_rows, "empty_bricks": empty}
    finally:
        shutil.rmtree(folder, ignore_errors=True)
