#pragma once
// Scene files (TOML) to typed settings, validated once here. Every error names the file, the
// line, the key and what is allowed; on error nothing is returned.
#include <string>
#include <string_view>
#include <vector>

#include "renderer/render_settings.h"
#include "world/scene.h"
#include "world/world.h"

namespace nephele {

struct SceneFile {
  Scene scene;
  WorldDynamics dynamics;  // wind, development schedules, automaton clouds
  RenderSettings render;
  ReferenceSettings reference;
};

// Allowed ranges shared by scene files and command-line overrides.
struct Limits {
  static constexpr int kMaxImageSide = 16384;      // GL_MAX_RENDERBUFFER_SIZE on llvmpipe
  static constexpr double kMaxCoordinate = 1.0e8;  // metres from the origin
  static constexpr double kMaxAltitude = 1.0e5;
  static constexpr double kMinVfov = 0.01, kMaxVfov = 179.0;
  // Angles in degrees, each allowed from -max to +max; sun azimuth and elevation follow
  // heading and pitch.
  static constexpr double kMaxHeading = 360.0, kMaxPitch = 90.0, kMaxRoll = 180.0;
  static constexpr double kMaxTime = 1.0e9;  // seconds of simulation time
  // Ellipsoid semi-axes and target sizes, metres: zero, negative and NaN are rejected.
  static constexpr double kMinRadius = 1.0e-3, kMaxRadius = 1.0e5;
  static constexpr int kMaxEllipsoidsPerCloud = 4096;
  // Automaton steps are simulated one by one: a scene with automaton clouds may start at most
  // a day into its simulation.
  static constexpr double kMaxAutomatonTime = 86400.0;
  static constexpr int kMaxAutomata = 256;
};

// Names of the render knobs in enum order, shared by scene files and the command line.
inline const std::vector<std::string> kTextureEvaluationNames{"baked", "procedural"};
inline const std::vector<std::string> kTermFilterNames{"fade", "cut", "none"};
inline const std::vector<std::string> kSkyPassesNames{"fused", "multipass"};
inline const std::vector<std::string> kEllipsoidPassesNames{"fused", "multipass"};
inline const std::vector<std::string> kEllipsoidOrderNames{"centre", "per-pixel"};
inline const std::vector<std::string> kLimbNames{"exact", "spotlight"};
inline const std::vector<std::string> kTileFormatNames{"rgba8", "float"};
inline const std::vector<std::string> kPhaseFunctionNames{"rayleigh", "cornette-shanks"};

// Position of `name` in `names`, or -1.
int nameIndex(const std::vector<std::string>& names, std::string_view name);

// Reads `path`. Returns an empty string on success, else the error.
std::string loadSceneFile(const std::string& path, SceneFile& out);
// Parses TOML text; `source_name` is the file name used in messages.
std::string parseSceneText(std::string_view text, const std::string& source_name, SceneFile& out);

// Checks the render knobs whose allowed values are not a plain range: "key: what is wrong
// (allowed: ...)", or empty when valid.
std::string validateRenderSettings(const RenderSettings& settings);

// Checks a camera after command-line overrides; empty string when valid.
std::string validateCamera(const Camera& camera);

}  // namespace nephele
