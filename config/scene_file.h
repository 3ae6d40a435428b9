#pragma once
// Scene files (TOML) to typed settings, validated once here. Every error names the file, the
// line, the key and what is allowed; on error nothing is returned.
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "renderer/render_knobs.h"
#include "renderer/render_settings.h"
#include "world/limits.h"
#include "world/scene.h"
#include "world/world.h"

namespace nephele {

struct SceneFile {
  Scene scene;
  WorldDynamics dynamics;  // wind, development schedules, automaton clouds
  RenderSettings render;
  // The CPU reference's settings, from `render` (its supersampling, the heaps and the sea).
  ReferenceSettings reference() const { return referenceSettingsOf(render); }
};

// Names of an automaton cloud's phase functions in enum order. The render knobs' names are
// in their table (renderer/render_knobs.inc).
inline const std::vector<std::string> kPhaseFunctionNames{"rayleigh", "cornette-shanks"};

// Position of `name` in `names`, or -1.
int nameIndex(const std::vector<std::string>& names, std::string_view name);

// Reads `path`. Returns an empty string on success, else the error.
std::string loadSceneFile(const std::string& path, SceneFile& out);
// Parses TOML text; `source_name` is the file name used in messages.
std::string parseSceneText(std::string_view text, const std::string& source_name, SceneFile& out);

// A cloud given as a JSON object with the keys of a scene file's [[cloud]] table (the socket
// protocol's add_cloud); `seed` seeds its texture unless the object names one. Errors name
// the key and what is allowed.
std::string parseCloudJson(const nlohmann::json& cloud, std::uint64_t seed, EllipsoidCloud& out);

namespace config_detail {
class TableReader;
}
// Reads a [[target]] table onto `target` (relative mesh paths are relative to `path`'s
// directory). With `extra_keys` the caller reads those keys and finishes the table.
void readTarget(config_detail::TableReader& t, const std::string& path, Target& target,
                std::vector<std::string> extra_keys = {});

// A target given as a JSON object with the keys of a scene file's [[target]] table (the socket
// protocol's add_target), without `mesh`; `type` starts it from one of `types` (the daemon
// config's [[entity_type]], which alone may name meshes). Errors name the key and what is
// allowed.
std::string parseTargetJson(const nlohmann::json& target, const std::vector<EntityType>& types,
                            Target& out);

// Checks a camera after command-line overrides; empty string when valid.
std::string validateCamera(const Camera& camera);

}  // namespace nephele
