#pragma once
// What one GL frame did, so that a user can see that a scene pays only for what it shows
// (`nephele render --stats`, the daemon's `stats`).
#include <string>
#include <utility>
#include <vector>

namespace nephele {

struct FrameStats {
  int sky_passes = 0;        // background and layer passes
  int ellipsoid_passes = 0;  // fused draws, tile composites and impostor billboards
  int atlas_passes = 0;      // multipass: tile passes into the atlas (Elinas)
  int automaton_passes = 0;  // volume marches
  int target_passes = 0;     // opaque target meshes
  int veil_passes = 0;       // the in-cloud veil
  // Per-pixel ellipsoid passes drawn from samples behind a thick veil (MODEL.md section 15)
  int sampled_passes = 0;
  int ellipsoids_drawn = 0;    // in view and drawn (directly or into an impostor)
  int ellipsoids_culled = 0;   // behind the eye, off screen, or with the eye inside
  int impostors_drawn = 0;     // far clouds drawn from an impostor
  int impostors_rendered = 0;  // impostors (re)rendered this frame
  // Gardner terms a pixel of the layers evaluates at most, summed over the layers drawn: the
  // term filter (MODEL.md section 2) drops terms above half the sampling frequency, at the
  // finest footprint a layer can show (straight above or below the camera).
  int layer_terms = 0;
  int layer_terms_total = 0;  // the layers' terms before the filter
  int volume_uploads = 0;     // automaton keyframe volumes sent to the GPU
  // Layer texels evaluated into clipmaps (MODEL.md section 2): every ring when a clipmap is
  // new, then only the strips the camera uncovers.
  int layer_texels_baked = 0;

  int passes() const {
    return sky_passes + ellipsoid_passes + atlas_passes + automaton_passes + target_passes +
           veil_passes;
  }
  // Every figure with its name, `passes` first: one list for the log line and the daemon.
  std::vector<std::pair<const char*, int>> fields() const;
  // One line of key=value pairs.
  std::string line() const;
};

}  // namespace nephele
