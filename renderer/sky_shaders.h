#pragma once
// GLSL for the sky passes: the background (sky gradient, ground) and one pass per cloud layer.
#include <string>

#include "renderer/render_settings.h"

namespace nephele {

// What a layer pass must compute; everything a scene does not need is compiled out.
struct LayerShaderVariant {
  enum class Texture { kBakedGardner, kProceduralGardner, kTable } texture = Texture::kBakedGardner;
  TermFilter term_filter = TermFilter::kFade;
  bool fog = false;
  bool specular = false;

  std::string key() const;
};

std::string polygonVertexSource();
std::string backgroundFragmentSource(bool fog);
std::string layerFragmentSource(const LayerShaderVariant& variant);

}  // namespace nephele
