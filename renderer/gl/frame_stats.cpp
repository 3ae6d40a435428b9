#include "renderer/gl/frame_stats.h"

#include <sstream>

namespace nephele {

std::vector<std::pair<const char*, int>> FrameStats::fields() const {
  return {{"passes", passes()},
          {"sky_passes", sky_passes},
          {"ellipsoid_passes", ellipsoid_passes},
          {"atlas_passes", atlas_passes},
          {"automaton_passes", automaton_passes},
          {"target_passes", target_passes},
          {"veil_passes", veil_passes},
          {"sampled_passes", sampled_passes},
          {"ellipsoids_drawn", ellipsoids_drawn},
          {"ellipsoids_culled", ellipsoids_culled},
          {"impostors_drawn", impostors_drawn},
          {"impostors_rendered", impostors_rendered},
          {"layer_terms", layer_terms},
          {"layer_terms_total", layer_terms_total},
          {"volume_uploads", volume_uploads},
          {"layer_texels_baked", layer_texels_baked}};
}

std::string FrameStats::line() const {
  std::ostringstream out;
  for (const auto& [name, value] : fields())
    out << (out.tellp() > 0 ? " " : "") << name << '=' << value;
  return out.str();
}

}  // namespace nephele
