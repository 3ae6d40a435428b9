#include "renderer/gl/ellipsoid_shaders.h"

#include "renderer/gl/sky_shaders.h"

namespace nephele {
namespace {

const char* kRecords = R"(
// One ellipsoid seen from the eye, everything camera-relative (see EllipsoidRenderer); the
// texels of record(i, k) in this order:
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
  vec4 order;      // z: the nearest a hit on it can be, metres (front-to-back order)
  vec4 envelope;   // its heap's envelope (MODEL.md section 14): centre - eye; w extinction
  vec4 inv_radii;  // 1 / the envelope's semi-axes; w: the share of the sunlight the other
                   // clouds above take (MODEL.md section 16), at its centre
};
// Records live in a buffer texture, kRecordTexels RGBA32F texels each: llvmpipe fetches texels
// for eight pixels at once, where a storage buffer is read one pixel at a time.
layout(binding = 13) uniform samplerBuffer u_records;
const int kRecordTexels = 19;
vec4 record(int i, int k) { return texelFetch(u_records, i * kRecordTexels + k); }
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
uniform vec4 u_scatter;  // x: 1 with the heap's light (MODEL.md section 14), else 0; y: g;
                         // z: the skin's wrap w (kSkinWrap) with the heap's light, else 0;
                         // w: the bend towards the envelope's normal (kHeapNormalBend)

vec3 toUnit(int i, vec3 v) {
  return vec3(dot(record(i, 0).xyz, v), dot(record(i, 1).xyz, v), dot(record(i, 2).xyz, v));
}
// W^T u: the quadric's gradient direction at unit-sphere point u.
vec3 gradientFromUnit(int i, vec3 u) {
  return u.x * record(i, 0).xyz + u.y * record(i, 1).xyz + u.z * record(i, 2).xyz;
}

// Nearest root s of |o + s W r| = 1, in units of r; negative when the ellipsoid is missed or
// lies behind the eye. Delta / 4 = |w|^2 - |o x w|^2 keeps far ellipsoids exact.
float hitEllipsoid(int i, vec3 r) {
  vec3 w = toUnit(i, r), o = record(i, 3).xyz;
  float a = dot(w, w);
  vec3 c = cross(o, w);
  float quarter_delta = a - dot(c, c);
  if (quarter_delta <= 0.0) return -1.0;
  float half_b = dot(o, w);
  float q = -(half_b + (half_b >= 0.0 ? 1.0 : -1.0) * sqrt(quarter_delta));
  return min(q / a, record(i, 3).w / q);
}

#ifdef SPOTLIGHT
layout(binding = 10) uniform sampler2D u_spotlight;  // 1 - rho^2 over [-1, 1]^2
#endif

// The limb function g (MODEL.md section 4) for view direction d.
float limbG(int i, vec3 d) {
  vec3 a = record(i, 4).xyz;
  float along = dot(d, a);
  if (along <= 0.0) return 0.0;
  vec3 q = d / along - a;
#ifdef SPOTLIGHT
  // Elinas: a radial texture projected from the eye along the cone's axis.
  vec2 st = vec2(dot(record(i, 8).xyz, q), dot(record(i, 9).xyz, q));
  return textureLod(u_spotlight, 0.5 + 0.5 * st, 0.0).r;
#else
  vec3 pq = vec3(dot(record(i, 5).xyz, q), dot(record(i, 6).xyz, q), dot(record(i, 7).xyz, q));
  return clamp(1.0 - dot(q, pq), 0.0, 1.0);
#endif
}

uniform float u_t0;  // Gardner's T0 and k, procedural or baked
uniform float u_k;

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
uniform float u_terms;

void addSolidTerm(int j, vec3 p, inout float sx, inout float sy) {
  float pz = kPi * gardnerSin(0.5 * u_fx[j] * p.z + u_half_z[j]);
  float px = kHalfPi * gardnerSin(0.5 * u_fy[j] * p.y + u_half_y[j]) + pz;
  float py = kHalfPi * gardnerSin(0.5 * u_fx[j] * p.x + u_half_x[j]) + pz;
  sx += u_amplitude[j] * gardnerSin(u_fx[j] * p.x + u_phase_x[j] + px);
  sy += u_amplitude[j] * gardnerSin(u_fy[j] * p.y + u_phase_y[j] + py);
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
#elif defined(BAKED_GARDNER)
// Gardner's sums baked (bakedSolidLayout): SX - T0 and SY - T0 of the lower terms over the
// period, of the upper terms over a u_fine_periods-th of it; each table's levels drop its
// terms as the term filter does, so trilinear filtering fades them out.
layout(binding = 9) uniform sampler3D u_volume;
layout(binding = 14) uniform sampler3D u_volume_fine;
uniform vec3 u_fine_origin;  // the eye's coordinate in the fine table, periods, in [0, 1)
uniform float u_fine_periods;
float solidValue(vec3 p, vec3 dpdx, vec3 dpdy) {
  vec3 fine = u_inv_period * u_fine_periods;
  vec2 s = vec2(u_t0) +
           textureGrad(u_volume, u_tex_origin + p * u_inv_period, dpdx * u_inv_period,
                       dpdy * u_inv_period).rg +
           textureGrad(u_volume_fine, u_fine_origin + p * fine, dpdx * fine, dpdy * fine).rg;
  return u_k * max(s.x, 0.0) * max(s.y, 0.0);
}
#else
// A periodic 3D texture: Perlin noise with ordinary mipmaps.
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

// Length of the ray p + s v (v unit, s >= 0) inside the envelope of ellipsoid i's heap, p
// camera-relative (envelopeChord).
float envelopeChord(int i, vec3 p, vec3 v) {
  vec3 inv = record(i, 18).xyz;
  vec3 o = (p - record(i, 17).xyz) * inv, w = v * inv;
  float a = dot(w, w), half_b = dot(o, w), c = dot(o, o) - 1.0;
  float quarter_delta = half_b * half_b - a * c;
  if (quarter_delta <= 0.0 || a <= 0.0) return 0.0;
  float root = sqrt(quarter_delta);
  return max(0.0, (-half_b + root) / a - max((-half_b - root) / a, 0.0));
}

// Two-stream transmittance of optical depth tau (diffuseTransmittance), asymmetry g.
float diffuseTransmittance(float tau) { return 1.0 / (1.0 + 0.75 * (1.0 - u_scatter.y) * tau); }

// Gardner eq. 8 with the light reaching surface point p of ellipsoid i through its heap
// (heapLightAt), plus the light scattered forward through the surface's translucence tr
// (MODEL.md section 14), times cloud and sun colour, fogged; n faces the viewer (and is lit
// as heapLitNormal bends it), r points at the surface from the eye, p camera-relative,
// `distance` in metres.
vec3 surfaceColour(int i, vec3 n, vec3 r, vec3 p, float it, float tr, float distance) {
  float extinction = record(i, 17).w;
  vec2 light = vec2(1.0);  // sun, sky
  float direct = 1.0;      // the unscattered beam, exp(-depth towards the sun)
  if (extinction > 0.0) {
    // heapLitNormal: n bent towards the envelope's outward normal, (p - c) / radii^2.
    vec3 inv = record(i, 18).xyz;
    vec3 gradient = (p - record(i, 17).xyz) * inv * inv;
    if (dot(gradient, gradient) > 0.0) n = normalize(mix(n, normalize(gradient), u_scatter.w));
    float toward_sun = 0.5 * (1.0 - clamp(dot(n, u_to_sun), -1.0, 1.0));
    float toward_sky = 0.5 * (1.0 - clamp(n.z, -1.0, 1.0));
    float sun_depth = extinction * toward_sun * envelopeChord(i, p, u_to_sun);
    light = vec2(diffuseTransmittance(sun_depth),
                 0.5 + 0.5 * diffuseTransmittance(extinction * toward_sky *
                                                  envelopeChord(i, p, vec3(0.0, 0.0, 1.0))));
    direct = exp(-sun_depth);
  }
  float outside = 1.0 - record(i, 18).w;
  light.x *= outside;
  direct *= outside;
  float n_dot_l = dot(n, u_to_sun);
  float diffuse = max((n_dot_l + u_scatter.z) / (1.0 + u_scatter.z), 0.0);
  float sun = light.x;
  float highlight = 0.0;
#ifdef SPECULAR
  if (n_dot_l > 0.0) {
    vec3 reflected = 2.0 * n_dot_l * n - u_to_sun;
    highlight = pow(max(dot(reflected, -normalize(r)), 0.0), u_shading.w);
  }
#endif
  float intensity = gardnerIntensity(u_shading, sun * diffuse, sun * highlight, it) +
                    u_shading.x * (light.y - 1.0);
  vec3 d = normalize(r);
  intensity += u_scatter.x * forwardScattered(direct, dot(d, u_to_sun)) * tr;
  return applyAir(intensity * u_cloud_colour, d, distance);
}

// Gardner eq. 11 given the threshold excess x = It - T1 - (T2 - T1)(1 - g): opacity 1 - TR.
float opacityFromExcess(float x) { return 1.0 - translucence(x, u_thresholds.z); }

// Premultiplied colour and opacity of ellipsoid i where the ray r meets it at s.
vec4 ellipsoidSurface(int i, vec3 r, float s) {
  vec3 p = s * r;
  vec3 n = normalize(gradientFromUnit(i, record(i, 3).xyz + s * toUnit(i, r)));
  if (dot(n, r) > 0.0) n = -n;  // turned towards the viewer
  // Ray differentials on the tangent plane: the hit moves by s (dr - r (n.dr) / (n.r)).
  vec3 drx = u_right * (2.0 / u_viewport.x), dry = u_up * (2.0 / u_viewport.y);
  float n_dot_r = min(dot(n, r), -1e-4 * length(r));
  vec3 dpdx = s * (drx - r * (dot(n, drx) / n_dot_r));
  vec3 dpdy = s * (dry - r * (dot(n, dry) / n_dot_r));
  float it = solidValue(p, dpdx, dpdy);
  float excess = it - u_thresholds.x - (u_thresholds.y - u_thresholds.x) * (1.0 - limbG(i, r));
  float opacity = opacityFromExcess(excess);
  float alpha = opacity * record(i, 4).w;
  return vec4(surfaceColour(i, n, r, p, it, 1.0 - opacity, s * length(r)) * alpha, alpha);
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
// The batch's screen bins, kPerPixelBinSize pixels a side, from bin u_bin_origin on, u_bins_x
// to a row: bin b lists its ellipsoids u_items[u_bins[b].x .. + u_bins[b].y) nearest first
// by the distance no hit on them can be nearer than (the record's order.z, metres).
layout(binding = 7) uniform isamplerBuffer u_bins;   // RG32I: first item, count
layout(binding = 8) uniform isamplerBuffer u_items;  // R32I
uniform ivec2 u_bin_origin;
uniform int u_bins_x;
uniform int u_bin_size;
uniform float u_opaque;  // the coverage past which the walk ends
#ifdef HISTORY
layout(location = 1) out vec4 o_history;  // a continuous view's first frame, kept
#endif
#ifdef SAMPLE_DISTANCE
uniform int u_bins_y;
// The distance in metres at which the walk's coverage passes 1/2 (of the last hit if it never
// does; 0 where nothing is hit): what a continuous view reprojects the sample by.
layout(location = 1) out float o_distance;
#endif

// Hits are ordered by (depth, ellipsoid index), so equal depths still have one order.
bool before(float s, int i, float t, int j) { return s < t || (s == t && i < j); }

// Ellipsoid i's hit on this pixel's ray where it shows, else -1.
float shownHit(int i, vec3 r, float limit) {
  float s = hitEllipsoid(i, r);
  return hitShows(r, s, limit) ? s : -1.0;
}

void main() {
  vec3 r = viewRay();
  float metres_per_unit = length(r);
  float limit = opaqueDistance(r) / metres_per_unit;
  ivec2 bin = ivec2(floor(FRAG_XY / float(u_bin_size))) - u_bin_origin;
#ifdef SAMPLE_DISTANCE
  // Samples shifted by a continuous view's offset reach one sample past the batch's bins on
  // either side, where nothing of the batch is.
  o_distance = 0.0;
  if (any(lessThan(bin, ivec2(0))) || bin.x >= u_bins_x || bin.y >= u_bins_y) discard;
  float depth = 0.0;
#endif
  ivec2 list = texelFetch(u_bins, bin.y * u_bins_x + bin.x).xy;
  // Front to back (MODEL.md section 15): the ellipsoids come nearest bound first, and a hit
  // that no ellipsoid still to come can be in front of is final. Up to four hits wait,
  // nearest first (depth d, ellipsoid id; empty slots at kNone). Each round tests ellipsoids
  // until the nearest waiting hit is final (or four wait: then the nearest goes first), then
  // composites the final hits; the walk ends once the pixel is opaque, since what lies
  // behind would add less than 1/1024. Shading stays out of the testing loop: llvmpipe runs
  // both sides of every branch, so a loop pays for all of its body on every turn.
  const float kNone = 3.0e38;
  const float kOpaque = u_opaque;
  vec4 d = vec4(kNone);
  ivec4 id = ivec4(-1);
  int waiting = 0, k = 0;
  float next = kNone;  // the bound of ellipsoid k, the next to test (kNone when none is left)
  vec4 result = vec4(0.0);
  while (result.a < kOpaque) {
    for (; k < list.y; ++k) {
      int i = texelFetch(u_items, list.x + k).x;
      next = record(i, 16).z / metres_per_unit;
      if (next >= limit) {
        k = list.y;
        break;
      }
      if (waiting == 4 || (waiting > 0 && d.x <= next)) break;
      float s = shownHit(i, r, limit);
      if (s < 0.0) continue;
      // Insert (s, i) in order with constant indices (llvmpipe spills indexed arrays).
      int at = int(before(d.x, id.x, s, i)) + int(before(d.y, id.y, s, i)) +
               int(before(d.z, id.z, s, i));
      d = vec4(at > 0 ? d.x : s, at > 1 ? d.y : (at == 1 ? s : d.x),
               at > 2 ? d.z : (at == 2 ? s : d.y), at == 3 ? s : d.z);
      id = ivec4(at > 0 ? id.x : i, at > 1 ? id.y : (at == 1 ? i : id.x),
                 at > 2 ? id.z : (at == 2 ? i : id.y), at == 3 ? i : id.z);
      ++waiting;
    }
    if (k >= list.y) next = kNone;
    if (waiting == 0) break;
    do {
#ifdef SAMPLE_DISTANCE
      if (result.a < 0.5) depth = d.x;
#endif
      result += (1.0 - result.a) * ellipsoidSurface(id.x, r, d.x);
      d = vec4(d.yzw, kNone);
      id = ivec4(id.yzw, -1);
      --waiting;
    } while (waiting > 0 && d.x <= next && result.a < kOpaque);
  }
  if (result.a <= 0.0) discard;
  o_colour = result;
#ifdef HISTORY
  o_history = result;
#endif
#ifdef SAMPLE_DISTANCE
  o_distance = depth * metres_per_unit;
#endif
}
)";

// Behind a thick veil (MODEL.md section 15, "behind the veil"): the walk's result at every
// SHADING_RATE-th pixel in x and y (sample c at pixel c * SHADING_RATE), blended over the
// blocks of pixels whose four corner samples agree. The CPU sorts the blocks from the samples
// it reads back; the others are walked (kFusedRest).
const char* kFusedBlend = R"(
layout(binding = 12) uniform sampler2D u_samples;  // bilinear: the blend in one fetch
void main() {
  vec2 at = floor(gl_FragCoord.xy) / float(SHADING_RATE) + 0.5;  // sample c's centre is c + 0.5
  o_colour = textureLod(u_samples, at / vec2(textureSize(u_samples, 0)), 0.0);
  if (o_colour.a <= 0.0) discard;
}
)";

// A continuous view's heaps (MODEL.md section 15, "reuse across frames"): this frame's
// samples, at one pixel in SHADING_RATE^2 from u_sample_origin, are exact where they stand;
// every other pixel takes the last frame's heaps reprojected to it by its samples' distance,
// the camera's motion and the clouds' drift, kept within the range of the four samples around
// it, or the samples' blend where the last frame cannot vouch for it. Blended over the frame
// and written as it is to the next frame's history.
const char* kFusedResolve = R"(
layout(location = 1) out vec4 o_history;
layout(binding = 12) uniform sampler2D u_samples;
layout(binding = 4) uniform sampler2D u_sample_distance;
layout(binding = 5) uniform sampler2D u_history;
uniform ivec2 u_sample_origin;  // the pixel of sample (0, 0)
uniform vec3 u_prev_x;          // the last frame's clip rows: right / (tan(vfov/2) aspect),
uniform vec3 u_prev_y;          // up / tan(vfov/2)
uniform vec3 u_prev_w;          // and forward
uniform vec3 u_prev_shift;      // a cloud point's position from the last eye, less from this one
const float kResolveMargin = 0.05;
vec4 resolve() {
  ivec2 q = ivec2(gl_FragCoord.xy) - u_sample_origin;
  ivec2 c = q / SHADING_RATE, f = q - c * SHADING_RATE;
  ivec2 top = textureSize(u_samples, 0) - 1;
  ivec2 c1 = min(c + 1, top);
  vec4 s00 = texelFetch(u_samples, c, 0), s10 = texelFetch(u_samples, ivec2(c1.x, c.y), 0);
  vec4 s01 = texelFetch(u_samples, ivec2(c.x, c1.y), 0), s11 = texelFetch(u_samples, c1, 0);
  if (f == ivec2(0)) return s00;
  vec2 w = vec2(f) / float(SHADING_RATE);
  vec4 blend = mix(mix(s00, s10, w.x), mix(s01, s11, w.x), w.y);
  // The four samples' distances in one gather (its texels c and c + 1 on each axis).
  vec4 d = textureGather(u_sample_distance, vec2(c + 1) / vec2(top + 1), 0);
  // The nearest of the samples that hit: an edge reprojects with its foreground.
  vec4 hit = mix(vec4(3.0e38), d, greaterThan(d, vec4(0.0)));
  float distance = min(min(hit.x, hit.y), min(hit.z, hit.w));
  if (distance >= 3.0e38) return blend;
  vec3 point = normalize(viewRay()) * distance + u_prev_shift;
  float depth = dot(point, u_prev_w);
  if (depth <= 0.0) return blend;
  vec2 uv = 0.5 * vec2(dot(point, u_prev_x), dot(point, u_prev_y)) / depth + 0.5;
  if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return blend;
  vec4 last = textureLod(u_history, uv, 0.0);
  // Where the last frame had nothing that this one's samples see, it cannot vouch.
  if (last.a <= 0.0 && blend.a > 0.0) return blend;
  // Kept within the four samples' range widened by that range and kResolveMargin either
  // side: soft detail between the samples survives, a stale surface (a heap since moved or
  // grown, what was hidden coming into view) does not.
  vec4 lo = min(min(s00, s10), min(s01, s11)), hi = max(max(s00, s10), max(s01, s11));
  vec4 margin = hi - lo + kResolveMargin;
  return clamp(last, max(lo - margin, 0.0), hi + margin);
}
void main() {
  o_colour = resolve();
  o_history = o_colour;
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
  o_colour = vec4(surfaceColour(u_index, n, p, p, it, 1.0 - opacityFromExcess(excess), length(p)), 0.0);
#endif
}
)";

const char* kComposite = R"(
uniform int u_index;
uniform vec2 u_atlas_size;
layout(binding = 11) uniform sampler2D u_atlas;
void main() {
  vec4 rect = record(u_index, 10), tile = record(u_index, 15);
  vec2 ndc = 2.0 * gl_FragCoord.xy / u_viewport - 1.0;
  vec2 uv = (ndc - rect.xy) / (rect.zw - rect.xy);
  vec2 texel = tile.xy + clamp(uv * tile.zw, vec2(0.5), tile.zw - 0.5);
  vec4 t = texture(u_atlas, texel / u_atlas_size);
  // Elinas' colour-matrix step, here in the shader: alpha = (It - T1 - (T2 - T1)(1 - g)) / D.
  float alpha = opacityFromExcess(t.a) * record(u_index, 4).w;
  vec3 r = viewRay();
  float s = hitEllipsoid(u_index, r);
  // A tile texel just outside the exact silhouette (no hit) stands at the ray's closest
  // approach to the centre, so a cloud drawn in several bands draws it in exactly one.
  if (s <= 0.0) s = max(dot(record(u_index, 14).xyz, r) / dot(r, r), 0.0);
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
  k += air ? 'f' : '-';
  k += specular ? 's' : '-';
  k += targets ? 't' : '-';
  k += history ? 'h' : '-';
  k += std::to_string(shading_rate);
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
  vec4 rect = record(v_index, 10);
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1);  // triangle strip
  gl_Position = vec4(mix(rect.xy, rect.zw, corner), 0.0, 1.0);
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
  v_position = mat3(record(u_index, 11).xyz, record(u_index, 12).xyz,
                    record(u_index, 13).xyz) * a_unit + record(u_index, 14).xyz;
  gl_Position = u_projection * vec4(v_position, 1.0);
}
)";
      return s;
    case EllipsoidProgram::kFusedBlend:
    case EllipsoidProgram::kFusedResolve:
    case EllipsoidProgram::kFusedRest:
      return s + R"(
// Pixel rectangles (x0, y0, x1, y1), two triangles each.
layout(binding = 6) uniform isamplerBuffer u_rects;
uniform vec2 u_viewport;
void main() {
  ivec4 q = texelFetch(u_rects, gl_VertexID / 6);
  int corner = gl_VertexID % 6;
  corner = corner < 3 ? corner : corner - 2;  // 0 1 2, 1 2 3
  vec2 p = vec2((corner & 1) != 0 ? q.z : q.x, (corner & 2) != 0 ? q.w : q.y);
  gl_Position = vec4(2.0 * p / u_viewport - 1.0, 0.0, 1.0);
}
)";
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
  if (layout.air) s += "#define AIR\n";
  if (layout.specular) s += "#define SPECULAR\n";
  if (layout.targets) s += "#define TARGETS\n";
  if (layout.history) s += "#define HISTORY\n";
  if (layout.spotlight) s += "#define SPOTLIGHT\n";
  if (layout.texture == SolidTextureKind::kProcedural) s += "#define PROCEDURAL\n";
  if (layout.texture == SolidTextureKind::kBakedGardner) s += "#define BAKED_GARDNER\n";
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
    case EllipsoidProgram::kFusedSamples:
      // Sample c stands at pixel c * rate + u_sample_origin (0 but in a continuous view).
      s += "#define SAMPLE_DISTANCE\nuniform ivec2 u_sample_origin;\n#define FRAG_XY "
           "(floor(gl_FragCoord.xy) * " +
           std::to_string(layout.shading_rate) + ".0 + vec2(u_sample_origin) + 0.5)\n";
      break;
    case EllipsoidProgram::kFusedBlend:
    case EllipsoidProgram::kFusedResolve:
      s += "#define SHADING_RATE " + std::to_string(layout.shading_rate) + "\n";
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
    case EllipsoidProgram::kFusedSamples:
    case EllipsoidProgram::kFusedRest:
      return s + kFusedPerPixel;
    case EllipsoidProgram::kFusedBlend:
      return s + kFusedBlend;
    case EllipsoidProgram::kFusedResolve:
      return s + kFusedResolve;
    case EllipsoidProgram::kTileComposite:
      return s + kComposite;
    default:
      return s + kTile;
  }
}

}  // namespace nephele
