// Mesh and point-cloud files. Every writer is atomic (temporary file, then rename).
#pragma once

#include <string>

#include "sdfcontour/types.h"

namespace sdfcontour {

enum class PlyFormat { Binary, Ascii };

/// Writes a mesh as PLY (binary little-endian by default), OBJ, OFF or binary STL (float32
/// corners, no shared vertices), chosen by the extension (.ply, .obj, .off or .stl; anything
/// else is an Error).
void write_mesh(const std::string& path, const Mesh& mesh,
                PlyFormat ply_format = PlyFormat::Binary);

/// Reads a triangle mesh from OBJ, PLY (ASCII or binary) or OFF; polygons are fan-triangulated.
/// Throws Error for an unreadable or malformed file or one without triangles.
Mesh read_mesh(const std::string& path);

/// Writes oriented points as PLY with float64 x y z nx ny nz properties.
void write_oriented_points(const std::string& path, const OrientedPoints& points,
                           PlyFormat ply_format = PlyFormat::Binary);

/// Reads oriented points (x y z nx ny nz) from a PLY file, ASCII or binary.
OrientedPoints read_oriented_points(const std::string& path);

}  // namespace sdfcontour
