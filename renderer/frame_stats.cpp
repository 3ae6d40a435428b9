#include "renderer/frame_stats.h"

#include <numeric>
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
          {"shadow_maps", shadow_maps},
          {"sampled_passes", sampled_passes},
          {"reused_passes", reused_passes},
          {"ellipsoids_drawn", ellipsoids_drawn},
          {"ellipsoids_culled", ellipsoids_culled},
          {"impostors_drawn", impostors_drawn},
          {"impostors_rendered", impostors_rendered},
          {"layer_terms", layer_terms},
          {"layer_terms_total", layer_terms_total},
          {"volume_uploads", volume_uploads},
          {"layer_texels_baked", layer_texels_baked},
          {"programs_compiled", programs_compiled}};
}

double FrameTimes::gpuTotal() const {
  return std::accumulate(gpu_ms.begin(), gpu_ms.end(), 0.0);
}

void FrameTimes::accumulate(const FrameTimes& other, double weight) {
  for (std::size_t i = 0; i < cpu_ms.size(); ++i) cpu_ms[i] += weight * other.cpu_ms[i];
  for (std::size_t i = 0; i < gpu_ms.size(); ++i) gpu_ms[i] += weight * other.gpu_ms[i];
  submit_ms += weight * other.submit_ms;
  wait_ms += weight * other.wait_ms;
  readback_ms += weight * other.readback_ms;
  encode_ms += weight * other.encode_ms;
}

std::vector<std::pair<std::string, double>> FrameTimes::fields() const {
  std::vector<std::pair<std::string, double>> out;
  for (std::size_t i = 0; i < cpu_ms.size(); ++i)
    out.emplace_back(std::string("cpu_") + kCpuStageNames[i], cpu_ms[i]);
  for (std::size_t i = 0; i < gpu_ms.size(); ++i)
    out.emplace_back(std::string("gpu_") + kGpuPassNames[i], gpu_ms[i]);
  out.emplace_back("submit", submit_ms);
  out.emplace_back("wait", wait_ms);
  out.emplace_back("readback", readback_ms);
  out.emplace_back("encode", encode_ms);
  return out;
}

std::string FrameStats::line() const {
  std::ostringstream out;
  for (const auto& [name, value] : fields())
    out << (out.tellp() > 0 ? " " : "") << name << '=' << value;
  out.precision(3);
  out << std::fixed;
  for (const auto& [name, ms] : times.fields()) out << ' ' << name << "_ms=" << ms;
  return out.str();
}

}  // namespace nephele
