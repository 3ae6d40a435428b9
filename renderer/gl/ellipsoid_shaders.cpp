#include "renderer/gl/ellipsoid_shaders.h"

#include "renderer/gl/sky_shaders.h"

namespace nephele {
namespace {

const char* kRecords = R"(
// One ellipsoid seen from the eye, everything camera-relative (see EllipsoidRenderer).
struct EllipsoidRecord {
  vec4 w[3];       // rows of W = S^-1 R^T: unit-sphere offset of a camera-relative point
  vec4 eye_unit;   // o = W (eye - centre); w: c = |o|^2 - 1 (> 0: the eye is outside)
  vec4 limb_axis;  // cone axis a; w: surface fade of the in-cloud model
  vec4 p[3];       // rows of P: g = 1 - q.P q with q = d / (d.a) - a
  vec4 l[2];       // rows of L, P = L^T L: spotlight texture coordinates
  vec4 rect;       // screen rectangle in NDC: x0, y0, x1, y1
  vec4 body[3];    // columns of R S: unit sphere to camera-relative offsets
  vec4 centre;     // centre - eye
  vec4 tile;       // atlas tile: texel origin xy, size zw
  vec4 light;      // x sunlight, y sky light reaching it through its heap (MODEL.md section 14)
};
layout(std430, binding = 0) readonly buffer EllipsoidRecords { EllipsoidRecord u_e[]; };
)";

const char* kCloud = R"(
const float kPi = 3.14159265358979;
const float kHalfPi = 1.5707963267948966;
uniform vec3 u_cloud_colour;  // cloud colour times sun colour
uniform vec4 u_shading;       // Gardner eq. 8: ambient a, texture t, specular s, shininess e
uniform vec3 u_thresholds;    // T1, T2, D
uniform vec3 u_to_sun;
uniform vec3 u_tex_origin;    // texture coordinate of the eye, periods, in [0, 1)
uniform vec3 u_inv_period;    // periods per metre
uniform vec2 u_scatter;       // x: 1 with the heap's light (MODEL.md section 14), else 0; y: g

vec3 toUnit(int i, vec3 v) {
  return vec3(dot(u_e[i].w[0].xyz, v), dot(u_e[i].w[1].xyz, v), dot(u_e[i].w[2].xyz, v));
}
// W^T u: the quadric's gradient direction at unit-sphere point u.
vec3 gradientFromUnit(int i, vec3 u) {
  return u.x * u_e[i].w[0].xyz + u.y * u_e[i].w[1].xyz + u.z * u_e[i].w[2].xyz;
}

// Nearest root s of |o + s W r| = 1, in units of r; negative when the ellipsoid is missed or
// lies behind the eye. Delta / 4 = |w|^2 - |o x w|^2 keeps far ellipsoids exact.
float hitEllipsoid(int i, vec3 r) {
  vec3 w = toUnit(i, r), o = u_e[i].eye_unit.xyz;
  float a = dot(w, w);
  vec3 c = cross(o, w);
  float quarter_delta = a - dot(c, c);
  if (quarter_delta <= 0.0) return -1.0;
  float half_b = dot(o, w);
  float q = -(half_b + (half_b >= 0.0 ? 1.0 : -1.0) * sqrt(quarter_delta));
  return min(q / a, u_e[i].eye_unit.w / q);
}

#ifdef SPOTLIGHT
layout(binding = 10) uniform sampler2D u_spotlight;  // 1 - rho^2 over [-1, 1]^2
#endif

// The limb function g (MODEL.md section 4) for view direction d.
float limbG(int i, vec3 d) {
  vec3 a = u_e[i].limb_axis.xyz;
  float along = dot(d, a);
  if (along <= 0.0) return 0.0;
  vec3 q = d / along - a;
#ifdef SPOTLIGHT
  // Elinas: a radial texture projected from the eye along the cone's axis.
  vec2 st = vec2(dot(u_e[i].l[0].xyz, q), dot(u_e[i].l[1].xyz, q));
  return textureLod(u_spotlight, 0.5 + 0.5 * st, 0.0).r;
#else
  vec3 pq = vec3(dot(u_e[i].p[0].xyz, q), dot(u_e[i].p[1].xyz, q), dot(u_e[i].p[2].xyz, q));
  return clamp(1.0 - dot(q, pq), 0.0, 1.0);
#endif
}

#if defined(PROCEDURAL)
// Gardner's solid texture per fragment (MODEL.md section 2); term j's phases at the eye are
// reduced modulo 2 pi on the CPU in double, so p is camera-relative.
uniform float u_fx[8];
uniform float u_fy[8];
uniform float u_amplitude[8];
uniform float u_phase_x[8];   // FX(j) eye.x + phx(j)
uniform float u_phase_y[8];   // FY(j) eye.y + phy(j)
uniform float u_half_x[8];    // FX(j) eye.x / 2
uniform float u_half_y[8];    // FY(j) eye.y / 2
uniform float u_half_z[8];    // FX(j) eye.z / 2
uniform float u_t0;
uniform float u_k;
uniform float u_terms;

void addSolidTerm(int j, vec3 p, inout float sx, inout float sy) {
  float pz = kPi * sin(0.5 * u_fx[j] * p.z + u_half_z[j]);
  float px = kHalfPi * sin(0.5 * u_fy[j] * p.y + u_half_y[j]) + pz;
  float py = kHalfPi * sin(0.5 * u_fx[j] * p.x + u_half_x[j]) + pz;
  sx += u_amplitude[j] * sin(u_fx[j] * p.x + u_phase_x[j] + px);
  sy += u_amplitude[j] * sin(u_fy[j] * p.y + u_phase_y[j] + py);
}

float solidValue(vec3 p, vec3 dpdx, vec3 dpdy) {
  float count = resolvedTerms(
      max(length(dpdx), length(dpdy)) * max(u_inv_period.x, u_inv_period.y), u_terms);
  int whole = int(count);
  float sx = u_t0, sy = u_t0;
  for (int j = 0; j < whole; ++j) addSolidTerm(j, p, sx, sy);
  float t = u_k * max(sx, 0.0) * max(sy, 0.0);
  float fraction = count - float(whole);
  if (fraction > 0.0) {
    addSolidTerm(whole, p, sx, sy);
    t = mix(t, u_k * max(sx, 0.0) * max(sy, 0.0), fraction);
  }
  return t;
}
#else
// A periodic 3D texture: Gardner baked with level l holding n - l terms (trilinear
// filtering fades the terms out), or Perlin noise with ordinary mipmaps.
layout(binding = 9) uniform sampler3D u_volume;
float solidValue(vec3 p, vec3 dpdx, vec3 dpdy) {
  return textureGrad(u_volume, u_tex_origin + p * u_inv_period, dpdx * u_inv_period,
                     dpdy * u_inv_period).r;
}
#endif

// L.sun P(cos theta) / (4 pi), P Cornette-Shanks (Shen eq. 11) with asymmetry g.
float forwardScattered(float sun, float c) {
  float g = u_scatter.y, g2 = g * g;
  return sun * 1.5 * (1.0 - g2) / (2.0 + g2) * (1.0 + c * c) /
         pow(max(1.0 + g2 - 2.0 * g * c, 1e-6), 1.5) / (4.0 * kPi);
}

// Gardner eq. 8 with the light reaching ellipsoid i through its heap, plus the light scattered
// forward through the surface's translucence tr (MODEL.md section 14), times cloud and sun
// colour, fogged; n faces the viewer, r points at the surface from the eye, `distance` in
// metres.
vec3 surfaceColour(int i, vec3 n, vec3 r, float it, float tr, float distance) {
  vec2 light = u_e[i].light.xy;
  float n_dot_l = dot(n, u_to_sun);
  float diffuse = max(n_dot_l, 0.0);
  float highlight = 0.0;
#ifdef SPECULAR
  if (n_dot_l > 0.0) {
    vec3 reflected = 2.0 * n_dot_l * n - u_to_sun;
    highlight = pow(max(dot(reflected, -normalize(r)), 0.0), u_shading.w);
  }
#endif
  float intensity = gardnerIntensity(u_shading, light.x * diffuse, light.x * highlight, it) +
                    u_shading.x * (light.y - 1.0);
  vec3 d = normalize(r);
  intensity += u_scatter.x * forwardScattered(light.x, dot(d, u_to_sun)) * tr;
  return applyFog(intensity * u_cloud_colour, d, distance);
}

// Gardner eq. 11 given the threshold excess x = It - T1 - (T2 - T1)(1 - g): opacity 1 - TR.
float opacityFromExcess(float x) { return 1.0 - translucence(x, u_thresholds.z); }

// Premultiplied colour and opacity of ellipsoid i where the ray r meets it at s.
vec4 ellipsoidSurface(int i, vec3 r, float s) {
  vec3 p = s * r;
  vec3 n = normalize(gradientFromUnit(i, u_e[i].eye_unit.xyz + s * toUnit(i, r)));
  if (dot(n, r) > 0.0) n = -n;  // turned towards the viewer
  // Ray differentials on the tangent plane: the hit moves by s (dr - r (n.dr) / (n.r)).
  vec3 drx = u_right * (2.0 / u_viewport.x), dry = u_up * (2.0 / u_viewport.y);
  float n_dot_r = min(dot(n, r), -1e-4 * length(r));
  vec3 dpdx = s * (drx - r * (dot(n, drx) / n_dot_r));
  vec3 dpdy = s * (dry - r * (dot(n, dry) / n_dot_r));
  float it = solidValue(p, dpdx, dpdy);
  float excess = it - u_thresholds.x - (u_thresholds.y - u_thresholds.x) * (1.0 - limbG(i, r));
  float opacity = opacityFromExcess(excess);
  float alpha = opacity * u_e[i].limb_axis.w;
  return vec4(surfaceColour(i, n, r, it, 1.0 - opacity, s * length(r)) * alpha, alpha);
}

// Whether a hit at s (units of r) shows in this pass: in front of the ground and targets,
// and in the pass's layer band.
bool hitShows(vec3 r, float s, float limit) { return s > 0.0 && s < limit && inBand(s * r.z); }
)";

const char* kFusedCentre = R"(
flat in int v_index;
void main() {
  vec3 r = viewRay();
  float s = hitEllipsoid(v_index, r);
  if (!hitShows(r, s, opaqueDistance(r) / length(r))) discard;
  o_colour = ellipsoidSurface(v_index, r, s);
}
)";

const char* kFusedPerPixel = R"(
layout(std430, binding = 2) readonly buffer BinItems { int u_items[]; };
flat in int v_first;  // this screen bin's ellipsoids: u_items[v_first .. v_first + v_count)
flat in int v_count;
const int kMaxHits = 8;

// Hits are ordered by (depth, ellipsoid index), so equal depths still have one order.
bool before(float s, int i, float t, int j) { return s < t || (s == t && i < j); }

// Ellipsoid i's hit on this pixel's ray where it shows, else -1.
float shownHit(int i, vec2 ndc, vec3 r, float limit) {
  vec4 rect = u_e[i].rect;
  if (any(lessThan(ndc, rect.xy)) || any(greaterThan(ndc, rect.zw))) return -1.0;
  float s = hitEllipsoid(i, r);
  return hitShows(r, s, limit) ? s : -1.0;
}

void main() {
  vec3 r = viewRay();
  vec2 ndc = 2.0 * gl_FragCoord.xy / u_viewport - 1.0;
  float limit = opaqueDistance(r) / length(r);
  // The nearest kMaxHits hits, sorted near to far; `total` counts every hit.
  float depth[kMaxHits];
  int index[kMaxHits];
  int n = 0, total = 0;
  for (int k = 0; k < v_count; ++k) {
    int i = u_items[v_first + k];
    float s = shownHit(i, ndc, r, limit);
    if (s < 0.0) continue;
    ++total;
    if (n == kMaxHits && !before(s, i, depth[n - 1], index[n - 1])) continue;
    int j = min(n, kMaxHits - 1);
    n = min(n + 1, kMaxHits);
    for (; j > 0 && before(s, i, depth[j - 1], index[j - 1]); --j) {
      depth[j] = depth[j - 1];
      index[j] = index[j - 1];
    }
    depth[j] = s;
    index[j] = i;
  }
  if (n == 0) discard;
  // "Over", accumulated front to back (the same sum), so that hits behind an opaque one are
  // never shaded; what they could add is below 1/1024.
  const float kOpaque = 1.0 - 1.0 / 1024.0;
  vec4 result = vec4(0.0);
  for (int j = 0; j < n && result.a < kOpaque; ++j)
    result += (1.0 - result.a) * ellipsoidSurface(index[j], r, depth[j]);
  // More hits than the stack holds (rare: a deep pile of translucent lobes): peel the rest
  // exactly, one nearest-remaining hit per round, so that every hit is composited in order.
  float last_s = depth[n - 1];
  int last_i = index[n - 1];
  for (int peeled = n; peeled < total && result.a < kOpaque; ++peeled) {
    float best_s = 1e38;
    int best_i = -1;
    for (int k = 0; k < v_count; ++k) {
      int i = u_items[v_first + k];
      float s = shownHit(i, ndc, r, limit);
      if (s < 0.0 || !before(last_s, last_i, s, i)) continue;
      if (best_i < 0 || before(s, i, best_s, best_i)) {
        best_s = s;
        best_i = i;
      }
    }
    if (best_i < 0) break;
    result += (1.0 - result.a) * ellipsoidSurface(best_i, r, best_s);
    last_s = best_s;
    last_i = best_i;
  }
  o_colour = result;
}
)";

const char* kTile = R"(
uniform int u_index;
in vec3 v_position;  // camera-relative point on the tessellated surface
in vec3 v_unit;      // the same point on the unit sphere
void main() {
  vec3 p = v_position;
#if defined(TILE_THRESHOLD) || defined(TILE_COLOUR)
  float it = solidValue(p, dFdx(p), dFdy(p));
#endif
#if defined(TILE_THRESHOLD)
  o_colour = vec4(0.0, 0.0, 0.0, it - u_thresholds.x);
#elif defined(TILE_LIMB)
  o_colour = vec4(0.0, 0.0, 0.0, (u_thresholds.y - u_thresholds.x) * (1.0 - limbG(u_index, p)));
#else
  vec3 n = normalize(gradientFromUnit(u_index, v_unit));
  if (dot(n, p) > 0.0) n = -n;
  float excess = it - u_thresholds.x - (u_thresholds.y - u_thresholds.x) * (1.0 - limbG(u_index, p));
  o_colour = vec4(surfaceColour(u_index, n, p, it, 1.0 - opacityFromExcess(excess), length(p)), 0.0);
#endif
}
)";

const char* kComposite = R"(
uniform int u_index;
uniform vec2 u_atlas_size;
layout(binding = 11) uniform sampler2D u_atlas;
void main() {
  vec4 rect = u_e[u_index].rect, tile = u_e[u_index].tile;
  vec2 ndc = 2.0 * gl_FragCoord.xy / u_viewport - 1.0;
  vec2 uv = (ndc - rect.xy) / (rect.zw - rect.xy);
  vec2 texel = tile.xy + clamp(uv * tile.zw, vec2(0.5), tile.zw - 0.5);
  vec4 t = texture(u_atlas, texel / u_atlas_size);
  // Elinas' colour-matrix step, here in the shader: alpha = (It - T1 - (T2 - T1)(1 - g)) / D.
  float alpha = opacityFromExcess(t.a) * u_e[u_index].limb_axis.w;
  vec3 r = viewRay();
  float s = hitEllipsoid(u_index, r);
  // A tile texel just outside the exact silhouette (no hit) stands at the ray's closest
  // approach to the centre, so a cloud drawn in several bands draws it in exactly one.
  if (s <= 0.0) s = max(dot(u_e[u_index].centre.xyz, r) / dot(r, r), 0.0);
  if (!hitShows(r, s, opaqueDistance(r) / length(r))) discard;
  o_colour = vec4(t.rgb * alpha, alpha);
}
)";

const char* kImpostor = R"(
layout(binding = 12) uniform sampler2D u_impostor;  // premultiplied colour, coverage
in vec2 v_uv;
in vec3 v_position;  // camera-relative point on the billboard
void main() {
  // The billboard stands for the cloud: hidden where the ground or a target is nearer, and
  // cut by the layer band at its own height.
  if (length(v_position) >= opaqueDistance(v_position) || !inBand(v_position.z)) discard;
  o_colour = texture(u_impostor, v_uv);
}
)";

const char* kVeil = R"(
uniform vec4 u_veil;  // premultiplied colour, opacity
void main() { o_colour = u_veil; }
)";

}  // namespace

std::string EllipsoidPassLayout::key() const {
  std::string k = "e";
  k += char('0' + int(program));
  k += char('0' + int(texture));
  k += char('0' + int(term_filter));
  k += spotlight ? 'l' : '-';
  k += fog ? 'f' : '-';
  k += specular ? 's' : '-';
  k += targets ? 't' : '-';
  return k;
}

std::string ellipsoidVertexSource(const EllipsoidPassLayout& layout) {
  std::string s = "#version 450 core\n";
  switch (layout.program) {
    case EllipsoidProgram::kFusedCentre:
      s += kRecords;
      s += R"(
uniform int u_first;
flat out int v_index;
void main() {
  v_index = u_first + gl_InstanceID;
  vec4 rect = u_e[v_index].rect;
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1);  // triangle strip
  gl_Position = vec4(mix(rect.xy, rect.zw, corner), 0.0, 1.0);
}
)";
      return s;
    case EllipsoidProgram::kFusedPerPixel:
      s += R"(
// Screen bins (Gardner sorted per scan-line region; here per square of pixels): each lists
// the ellipsoids whose rectangles overlap it.
struct Bin {
  vec4 rect;    // NDC x0, y0, x1, y1
  ivec4 items;  // first, count
};
layout(std430, binding = 1) readonly buffer Bins { Bin u_bins[]; };
flat out int v_first;
flat out int v_count;
void main() {
  Bin bin = u_bins[gl_InstanceID];
  v_first = bin.items.x;
  v_count = bin.items.y;
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1);  // triangle strip
  gl_Position = vec4(mix(bin.rect.xy, bin.rect.zw, corner), 0.0, 1.0);
}
)";
      return s;
    case EllipsoidProgram::kTileThreshold:
    case EllipsoidProgram::kTileLimb:
    case EllipsoidProgram::kTileColour:
      s += kRecords;
      s += R"(
layout(location = 0) in vec3 a_unit;
uniform int u_index;
uniform mat4 u_projection;  // the tile's off-axis frustum, from camera-relative world
out vec3 v_position;
out vec3 v_unit;
void main() {
  v_unit = a_unit;
  v_position = mat3(u_e[u_index].body[0].xyz, u_e[u_index].body[1].xyz,
                    u_e[u_index].body[2].xyz) * a_unit + u_e[u_index].centre.xyz;
  gl_Position = u_projection * vec4(v_position, 1.0);
}
)";
      return s;
    case EllipsoidProgram::kImpostor:
      return s + R"(
uniform vec3 u_corner[4];  // camera-relative billboard corners, in triangle-strip order
uniform vec3 u_clip_x;     // right / (tan(vfov/2) aspect)
uniform vec3 u_clip_y;     // up / tan(vfov/2)
uniform vec3 u_clip_w;     // forward
out vec2 v_uv;
out vec3 v_position;
void main() {
  vec3 p = u_corner[gl_VertexID];
  v_position = p;
  v_uv = vec2(gl_VertexID & 1, gl_VertexID >> 1);
  gl_Position = vec4(dot(p, u_clip_x), dot(p, u_clip_y), 0.0, dot(p, u_clip_w));
}
)";
    default:
      return polygonVertexSource();
  }
}

std::string ellipsoidFragmentSource(const EllipsoidPassLayout& layout) {
  std::string s = "#version 450 core\n";
  if (layout.fog) s += "#define FOG\n";
  if (layout.specular) s += "#define SPECULAR\n";
  if (layout.targets) s += "#define TARGETS\n";
  if (layout.spotlight) s += "#define SPOTLIGHT\n";
  if (layout.texture == SolidTextureKind::kProcedural) s += "#define PROCEDURAL\n";
  if (layout.term_filter == TermFilter::kCut) s += "#define FILTER_CUT\n";
  if (layout.term_filter == TermFilter::kNone) s += "#define FILTER_NONE\n";
  switch (layout.program) {
    case EllipsoidProgram::kTileThreshold:
      s += "#define TILE_THRESHOLD\n";
      break;
    case EllipsoidProgram::kTileLimb:
      s += "#define TILE_LIMB\n";
      break;
    case EllipsoidProgram::kTileColour:
      s += "#define TILE_COLOUR\n";
      break;
    default:
      break;
  }
  s += viewShaderSource();
  if (layout.program == EllipsoidProgram::kVeil) return s + kVeil;
  if (layout.program == EllipsoidProgram::kImpostor) return s + kImpostor;
  s += kRecords;
  s += kCloud;
  switch (layout.program) {
    case EllipsoidProgram::kFusedCentre:
      return s + kFusedCentre;
    case EllipsoidProgram::kFusedPerPixel:
      return s + kFusedPerPixel;
    case EllipsoidProgram::kTileComposite:
      return s + kComposite;
    default:
      return s + kTile;
  }
}

}  // namespace nephele
