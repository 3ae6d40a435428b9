#pragma once
// Opaque objects for sensor simulation (targets): a box, an ellipsoid or a triangle mesh,
// placed and oriented like every body (MODEL.md section 1). Clouds hide them and they hide
// clouds, per pixel.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "world/camera.h"
#include "world/sky.h"

namespace nephele {

// Vertices in body coordinates (x right, y forward, z up), metres before scaling.
struct TriangleMesh {
  std::vector<glm::dvec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

enum class TargetShape { kBox, kEllipsoid, kMesh };

struct Target {
  std::string name;
  TargetShape shape = TargetShape::kBox;
  glm::dvec3 centre{0.0, 0.0, 1000.0};
  Orientation orientation;
  // Box: half-extents; ellipsoid: semi-axes; mesh: scale per body axis.
  glm::dvec3 size{10.0, 10.0, 3.0};
  glm::dvec3 colour{0.35, 0.35, 0.38};       // linear RGB albedo
  std::shared_ptr<const TriangleMesh> mesh;  // for kMesh
};

// A kind of target a host names by number (a CIGI entity type) or by name: shape, size, colour
// and mesh, from the daemon config's [[entity_type]]. Placed targets start from it.
struct EntityType {
  int id = 0;
  std::string name;
  Target prototype;
};

// Targets are Lambertian with a fixed ambient share: colour * sun * (a + (1 - a) S max(0, N.L)),
// N turned towards the viewer, S the share of the sunlight the clouds above let through
// (MODEL.md section 16; world/formulas/shadow.h targetLight).
glm::dvec3 targetRadiance(const Target& target, glm::dvec3 normal, glm::dvec3 to_sun,
                          glm::dvec3 to_viewer, const Sun& sun, double sunlight = 1.0);

struct TargetHit {
  double distance;    // along the unit ray
  glm::dvec3 normal;  // world, unit, not yet turned
};

// Nearest hit in front of `eye` along the unit `direction`.
std::optional<TargetHit> intersectTarget(const Target& target, glm::dvec3 eye,
                                         glm::dvec3 direction);

// The mesh's triangles in body coordinates after scaling (box and ellipsoid are analytic).
std::vector<glm::dvec3> scaledMeshVertices(const Target& target);

}  // namespace nephele
