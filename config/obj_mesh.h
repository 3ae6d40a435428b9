#pragma once
// Wavefront OBJ triangle meshes for targets: `v x y z` and `f` statements (polygons are
// fanned into triangles; v/vt/vn and negative indices accepted). Texture coordinates,
// normals, groups and materials are ignored. Coordinates are taken as body coordinates
// (x right, y forward, z up), in metres.
#include <string>

#include "world/target.h"

namespace nephele {

inline constexpr std::size_t kMaxObjTriangles = 1'000'000;

// Empty string on success; else the error with file and line. `out` is untouched on error.
std::string loadObjMesh(const std::string& path, TriangleMesh& out);
std::string parseObjText(const std::string& text, const std::string& source_name,
                         TriangleMesh& out);

}  // namespace nephele
