#include "config/obj_mesh.h"

#include "config/table_reader.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace nephele {

std::string parseObjText(const std::string& text, const std::string& source_name,
                         TriangleMesh& out) {
  TriangleMesh mesh;
  std::istringstream lines(text);
  std::string line;
  int line_number = 0;
  auto error = [&](const std::string& what) {
    return source_name + ":" + std::to_string(line_number) + ": " + what;
  };
  while (std::getline(lines, line)) {
    ++line_number;
    std::istringstream words(line);
    std::string keyword;
    if (!(words >> keyword) || keyword[0] == '#') continue;
    if (keyword == "v") {
      glm::dvec3 v;
      for (int i = 0; i < 3; ++i) {
        std::string word;
        words >> word;
        const char* end = word.data() + word.size();
        auto [ptr, ec] = std::from_chars(word.data(), end, v[i]);
        if (word.empty() || ec != std::errc() || ptr != end || !std::isfinite(v[i]))
          return error("vertex needs three finite numbers (got \"" + line + "\")");
      }
      mesh.vertices.push_back(v);
    } else if (keyword == "f") {
      std::vector<std::uint32_t> face;
      for (std::string word; words >> word;) {
        long index = 0;
        const char* end = word.data() + word.size();
        auto [ptr, ec] = std::from_chars(word.data(), end, index);
        if (ec != std::errc() || (ptr != end && *ptr != '/'))
          return error("face index \"" + word + "\" is not an integer");
        const long count = long(mesh.vertices.size());
        const long resolved = index < 0 ? count + index : index - 1;  // OBJ is 1-based
        if (index == 0 || resolved < 0 || resolved >= count)
          return error("face index " + std::to_string(index) + " is out of range (allowed: 1 to " +
                       std::to_string(count) + ", or -1 to -" + std::to_string(count) + ")");
        face.push_back(std::uint32_t(resolved));
      }
      if (face.size() < 3) return error("a face needs at least three vertices");
      for (std::size_t i = 1; i + 1 < face.size(); ++i)
        mesh.triangles.push_back({face[0], face[i], face[i + 1]});
      if (mesh.triangles.size() > kMaxObjTriangles)
        return error("more than " + std::to_string(kMaxObjTriangles) + " triangles");
    }
    // vt, vn, o, g, s, usemtl, mtllib and others do not shape the mesh.
  }
  if (mesh.triangles.empty()) return source_name + ": no faces (a mesh needs f statements)";
  out = std::move(mesh);
  return "";
}

std::string loadObjMesh(const std::string& path, TriangleMesh& out) {
  std::string text;
  if (std::string e = config_detail::readTextFile(path, "mesh file", text); !e.empty()) return e;
  return parseObjText(text, path, out);
}

}  // namespace nephele
