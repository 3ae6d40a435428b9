#include "renderer/sky_shaders.h"

namespace nephele {
namespace {

// The view (camera-relative: the camera sits at the origin, only its altitude is known to
// the shader), the output, and fog (SPEC: fog is unlit and applied per surface by its
// camera distance, which composites exactly under "over").
const char* kCommon = R"(
uniform vec3 u_right;    // image-plane basis, scaled by tan(vfov/2) * aspect
uniform vec3 u_up;       // scaled by tan(vfov/2)
uniform vec3 u_forward;
uniform vec2 u_viewport;
uniform float u_camera_z;
out vec4 o_colour;
const float kFar = 1e30;

vec3 viewRay() {
  vec2 ndc = 2.0 * gl_FragCoord.xy / u_viewport - 1.0;
  return u_right * ndc.x + u_up * ndc.y + u_forward;
}

#ifdef FOG
uniform float u_fog_top;
uniform float u_fog_sigma;
uniform vec3 u_fog_colour;

// Length inside the slab 0 <= z <= top of the unit ray from the camera, up to `distance`.
float fogPathLength(vec3 d, float distance) {
  float enter = 0.0, leave = distance;
  if (abs(d.z) < 1e-9) {
    if (u_camera_z < 0.0 || u_camera_z > u_fog_top) return 0.0;
  } else {
    float s0 = -u_camera_z / d.z, s1 = (u_fog_top - u_camera_z) / d.z;
    enter = max(enter, min(s0, s1));
    leave = min(leave, max(s0, s1));
  }
  return max(leave - enter, 0.0);
}

vec3 applyFog(vec3 colour, vec3 d, float distance) {
  float transmittance = exp(-u_fog_sigma * fogPathLength(d, distance));
  return mix(u_fog_colour, colour, transmittance);
}
#endif
)";

const char* kBackground = R"(
uniform vec3 u_zenith;
uniform vec3 u_horizon;
uniform vec3 u_ground;

void main() {
  vec3 d = normalize(viewRay());
  vec3 colour;
  float distance;
  if (d.z < 0.0) {
    colour = u_ground;
    distance = u_camera_z / -d.z;
  } else {
    colour = u_horizon + (u_zenith - u_horizon) * sqrt(d.z);  // SPEC section 5 gradient
    distance = kFar;
  }
#ifdef FOG
  colour = applyFog(colour, d, distance);
#endif
  o_colour = vec4(colour, 0.0);
}
)";

const char* kLayer = R"(
uniform float u_height;     // layer altitude minus camera altitude, never 0
uniform vec3 u_colour;      // layer colour times sun colour
uniform vec3 u_to_sun;
uniform vec4 u_shading;     // ambient a, texture fraction t, specular s, shininess e
uniform float u_threshold;  // T1
uniform float u_transition; // D
uniform vec2 u_origin;      // texture coordinate under the camera, in periods, in [0, 1)
uniform vec2 u_inv_period;  // periods per metre
uniform float u_terms;      // n

// Number of Gardner terms a pixel resolves; its footprint is in periods (SPEC section 2).
float termCount(float footprint) {
#if defined(FILTER_NONE)
  return u_terms;
#else
  float highest_resolved = log2(0.5 / footprint);
#if defined(FILTER_CUT)
  return clamp(floor(highest_resolved), 0.0, u_terms);
#else
  return clamp(highest_resolved - 1.0, 0.0, u_terms);
#endif
#endif
}

#if defined(TEXTURE_BAKED) || defined(TEXTURE_TABLE)
uniform sampler2D u_table;
#endif

#if defined(TEXTURE_PROCEDURAL)
// Per-term constants; the local origin's phase is reduced modulo 2 pi on the CPU in double.
uniform float u_fx[8];
uniform float u_fy[8];
uniform float u_amplitude[8];
uniform float u_phase_x[8];       // FX(i) * origin.x + phx(i), mod 2 pi
uniform float u_phase_y[8];       // FY(i) * origin.y + phy(i), mod 2 pi
uniform float u_half_phase_x[8];  // 0.5 FX(i) * origin.x, mod 2 pi
uniform float u_half_phase_y[8];  // 0.5 FY(i) * origin.y, mod 2 pi
uniform float u_t0;
uniform float u_k;
const float kHalfPi = 1.5707963267948966;

void addTerm(int i, vec2 p, inout float sx, inout float sy) {
  float px = kHalfPi * sin(0.5 * u_fy[i] * p.y + u_half_phase_y[i]);
  float py = kHalfPi * sin(0.5 * u_fx[i] * p.x + u_half_phase_x[i]);
  sx += u_amplitude[i] * sin(u_fx[i] * p.x + u_phase_x[i] + px);
  sy += u_amplitude[i] * sin(u_fy[i] * p.y + u_phase_y[i] + py);
}

float gardner(vec2 p, float count) {
  int whole = int(count);
  float sx = u_t0, sy = u_t0;
  for (int i = 0; i < whole; ++i) addTerm(i, p, sx, sy);
  float t = u_k * max(sx, 0.0) * max(sy, 0.0);
  float fraction = count - float(whole);
  if (fraction > 0.0) {
    addTerm(whole, p, sx, sy);
    t = mix(t, u_k * max(sx, 0.0) * max(sy, 0.0), fraction);
  }
  return t;
}
#endif

// T at offset p (metres from the camera) with the pixel's footprint derivatives.
float textureValue(vec2 p, vec2 dpdx, vec2 dpdy) {
  vec2 gx = dpdx * u_inv_period, gy = dpdy * u_inv_period;
#if defined(TEXTURE_TABLE)
  return textureGrad(u_table, u_origin + p * u_inv_period, gx, gy).r;
#else
  float count = termCount(max(length(gx), length(gy)));
#if defined(TEXTURE_BAKED)
  // Mip level l holds the truncation to n - l terms.
  return textureLod(u_table, u_origin + p * u_inv_period, u_terms - count).r;
#else
  return gardner(p, count);
#endif
#endif
}

float translucence(float excess) {  // Gardner eq. 9, D = 0 a hard threshold
  if (u_transition <= 0.0) return excess <= 0.0 ? 1.0 : 0.0;
  return clamp(1.0 - excess / u_transition, 0.0, 1.0);
}

void main() {
  vec3 r = viewRay();
  // Rays that never meet the plane are outside the drawn polygon but for a margin.
  if (r.z * u_height <= 0.0) discard;
  // Near the horizon keep the hit finite; its footprint is then far too large for any term.
  float rz = sign(u_height) * max(abs(r.z), 1e-6 * length(r));
  float s = u_height / rz;
  vec2 p = s * r.xy;
  // Exact derivatives of the hit point per pixel step (the plane's perspective Jacobian).
  float inv_rz2 = u_height / (rz * rz);
  vec2 dpdx = (u_right.xy * rz - r.xy * u_right.z) * inv_rz2 * (2.0 / u_viewport.x);
  vec2 dpdy = (u_up.xy * rz - r.xy * u_up.z) * inv_rz2 * (2.0 / u_viewport.y);

  float it = textureValue(p, dpdx, dpdy);
  float tr = translucence(it - u_threshold);

  vec3 to_viewer = -normalize(r);
  vec3 normal = vec3(0.0, 0.0, u_height > 0.0 ? -1.0 : 1.0);  // turned towards the viewer
  float n_dot_l = dot(normal, u_to_sun);
  float lit = max(n_dot_l, 0.0);
#ifdef SPECULAR
  float highlight = 0.0;
  if (n_dot_l > 0.0) {
    vec3 reflected = 2.0 * n_dot_l * normal - u_to_sun;
    highlight = pow(max(dot(reflected, to_viewer), 0.0), u_shading.w);
  }
  lit = (1.0 - u_shading.z) * lit + u_shading.z * highlight;
#endif
  float a = u_shading.x, t = u_shading.y;
  float intensity = (1.0 - a) * ((1.0 - t) * lit + t * it) + a;  // Gardner eq. 8
  vec3 colour = intensity * u_colour;
#ifdef FOG
  colour = applyFog(colour, -to_viewer, s * length(r));
#endif
  o_colour = vec4(colour, 1.0 - tr);
}
)";

std::string header(bool fog) {
  std::string s = "#version 450 core\n";
  if (fog) s += "#define FOG\n";
  return s;
}

}  // namespace

std::string LayerShaderVariant::key() const {
  return "layer/" + std::to_string(int(texture)) + "/" + std::to_string(int(term_filter)) + "/" +
         std::to_string(fog) + std::to_string(specular);
}

std::string polygonVertexSource() {
  return R"(#version 450 core
uniform vec2 u_polygon[8];  // convex polygon in normalised device coordinates, a triangle fan
void main() { gl_Position = vec4(u_polygon[gl_VertexID], 0.0, 1.0); }
)";
}

std::string backgroundFragmentSource(bool fog) {
  return header(fog) + kCommon + kBackground;
}

std::string layerFragmentSource(const LayerShaderVariant& variant) {
  std::string s = header(variant.fog);
  switch (variant.texture) {
    case LayerShaderVariant::Texture::kBakedGardner:
      s += "#define TEXTURE_BAKED\n";
      break;
    case LayerShaderVariant::Texture::kProceduralGardner:
      s += "#define TEXTURE_PROCEDURAL\n";
      break;
    case LayerShaderVariant::Texture::kTable:
      s += "#define TEXTURE_TABLE\n";
      break;
  }
  if (variant.term_filter == TermFilter::kCut) s += "#define FILTER_CUT\n";
  if (variant.term_filter == TermFilter::kNone) s += "#define FILTER_NONE\n";
  if (variant.specular) s += "#define SPECULAR\n";
  return s + kCommon + kLayer;
}

}  // namespace nephele
