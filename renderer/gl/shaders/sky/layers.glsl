
uniform float u_height[kSlots];     // layer altitude minus camera altitude, never 0
uniform vec3 u_colour[kSlots];      // layer colour times sun colour
uniform vec4 u_shading[kSlots];     // Gardner eq. 8: ambient a, texture t, specular s, shininess e
uniform float u_threshold[kSlots];  // T1
uniform float u_transition[kSlots]; // D
uniform vec2 u_origin[kSlots];      // texture coordinate under the camera, periods, in [0, 1)
uniform vec2 u_inv_period[kSlots];  // periods per metre
uniform float u_terms[kSlots];      // n
#ifdef REGIONS
uniform vec4 u_region[kSlots];       // centre from the camera (m), cos and sin of heading
uniform vec4 u_region_size[kSlots];  // half sizes (m, 1e30 unbounded), edge, front transition
uniform float u_region_side[kSlots]; // front side -1 or 1, 0 for none
uniform vec2 u_hole[kSlots];         // a far deck's hole around the camera and its band, m
uniform vec2 u_far[kSlots];          // a far deck's coverage and side ratio (0 none)
uniform float u_far_threshold[kSlots * (kFarCoverSteps + 1)];  // its T1 at cover 0, 1/16, ..., 1
#endif
uniform vec3 u_to_sun;

struct LayerHit {
  vec2 p;        // hit point relative to the camera, metres
  vec2 dpdx;     // its change per pixel step right
  vec2 dpdy;     // and up
  float distance;
};

// Hit of the view ray on the plane h metres above the camera (slot i's: hitLayer); the caller
// has checked that the ray meets it.
LayerHit hitPlane(float h, vec3 r) {
  // Near the horizon keep the hit finite; its footprint is then far too large for any term. The
  // ground from a camera on it (h = 0) is hit at the eye.
  float rz = (h < 0.0 ? -1.0 : 1.0) * max(abs(r.z), 1e-6 * length(r));
  LayerHit hit;
  hit.p = (h / rz) * r.xy;
  // Exact derivatives of the hit point per pixel (the plane's perspective Jacobian).
  float scale = h / (rz * rz);
  hit.dpdx = (u_right.xy * rz - r.xy * u_right.z) * scale * (2.0 / u_viewport.x);
  hit.dpdy = (u_up.xy * rz - r.xy * u_up.z) * scale * (2.0 / u_viewport.y);
  hit.distance = (h / rz) * length(r);
  return hit;
}
LayerHit hitLayer(int i, vec3 r) { return hitPlane(u_height[i], r); }

vec2 layerCoordinate(int i, LayerHit hit) { return u_origin[i] + hit.p * u_inv_period[i]; }

// Number of Gardner terms a pixel of slot i resolves.
float termCount(int i, LayerHit hit) {
  return resolvedTerms(
      max(length(hit.dpdx * u_inv_period[i]), length(hit.dpdy * u_inv_period[i])), u_terms[i],
      kTermFilter);
}

// Baked Gardner: level l holds the truncation to n - l terms in red and to n - l - 1 in
// green, so one bilinear fetch gives both truncations the fade blends.
float bakedValue(sampler2D table, int i, LayerHit hit) {
  float lod = u_terms[i] - termCount(i, hit);
  float level = floor(lod);
  vec2 t = textureLod(table, layerCoordinate(i, hit), level).rg;
  return mix(t.r, t.g, lod - level);
}

// Tabulated noise: trilinear mipmapping with the exact footprint.
float tableValue(sampler2D table, int i, LayerHit hit) {
  return textureGrad(table, layerCoordinate(i, hit), hit.dpdx * u_inv_period[i],
                     hit.dpdy * u_inv_period[i]).r;
}

#ifdef PROCEDURAL
// Per-term constants, slot i's term j at [8 i + j], and per component (u_components of them,
// at most kComponents, once the lattice is broken: GardnerTexture::components) at
// [kComponents (8 i + j) + c]; the local origin's phases are reduced modulo 2 pi on the CPU
// in double. Packed in vectors: llvmpipe loads each element of a uniform array that is
// indexed by a variable for every fragment.
uniform vec3 u_term[kSlots * 8];       // FX(j), FY(j), the amplitude of one component
uniform int u_components[kSlots * 8];  // of each term
// The component's X axis in SX (xy) and in SY (zw), (cos, sin) times its scale; (1, 0) for
// Gardner's lattice.
uniform vec4 u_axes[kSlots * 8 * kComponents];
// In the component's axes and mod 2 pi: FX(j) origin.x + phx(j), FY(j) origin.y + phy(j),
// FX(j) origin.x / 2, FY(j) origin.y / 2.
uniform vec4 u_phases[kSlots * 8 * kComponents];
uniform float u_t0[kSlots];
uniform float u_k[kSlots];
const float kHalfPi = 1.5707963267948966;

// Term j of slot i into SX and SY (GardnerTexture::addTerm), each component in its own axes;
// the origin's phases above were taken in the same axes.
void addTerm(int i, int j, vec2 p, inout float sx, inout float sy) {
  int t = 8 * i + j;
  vec3 term = u_term[t];
  for (int c = 0; c < u_components[t]; ++c) {
    int k = kComponents * t + c;
    vec4 axes = u_axes[k], phases = u_phases[k];
    vec2 q1 = vec2(axes.x * p.x + axes.y * p.y, axes.x * p.y - axes.y * p.x);
    vec2 q2 = vec2(axes.z * p.x + axes.w * p.y, axes.z * p.y - axes.w * p.x);
    float px = kHalfPi * gardnerSin(0.5 * term.y * q1.y + phases.w);
    float py = kHalfPi * gardnerSin(0.5 * term.x * q2.x + phases.z);
    sx += term.z * gardnerSin(term.x * q1.x + phases.x + px);
    sy += term.z * gardnerSin(term.y * q2.y + phases.y + py);
  }
}

// T of slot i at p (metres from the phases' origin) truncated to `count` terms, a fractional
// count blending floor(count) and floor(count) + 1 (GardnerTexture::planar).
float truncatedValue(int i, vec2 p, float count) {
  int whole = int(count);
  float sx = u_t0[i], sy = u_t0[i];
  for (int j = 0; j < whole; ++j) addTerm(i, j, p, sx, sy);
  float t = textureFromSums(sx, sy, u_k[i]);
  float fraction = count - float(whole);
  if (fraction > 0.0) {
    addTerm(i, whole, p, sx, sy);
    t = mix(t, textureFromSums(sx, sy, u_k[i]), fraction);
  }
  return t;
}

float proceduralValue(int i, LayerHit hit) { return truncatedValue(i, hit.p, termCount(i, hit)); }
#endif

#ifdef CLIPMAP
// The clipmap of a texture that never repeats (MODEL.md section 2, "Clipmap"; LayerClipmaps):
// ring l of slot i holds T truncated to n - l terms on a lattice of texel u_clip_texel[i] 2^l
// metres (the footprint at which the term filter keeps exactly n - l terms), centred near the
// camera; the texel of lattice index k is stored at k mod N. u_clip_offset[kRings i + l] is the
// camera's lattice coordinate in ring l modulo N. A pixel reads the two rings its footprint
// falls between, as the per-pixel fade does, or coarser ones where the finer ring does not
// reach: a ring is read within N/4 of its centre and blended into the next out to N/2.
const int kRings = 8;
uniform vec2 u_clip_texel[kSlots];
uniform vec2 u_clip_offset[kSlots * kRings];
uniform float u_clip_size[kSlots];      // N
uniform float u_clip_rings[kSlots];     // n: ring n and beyond hold T with no term
uniform float u_clip_constant[kSlots];  // that T, k T0^2
uniform float u_clip_finest[kSlots];    // the finest ring filled, with all coarser ones

float clipmapValue(sampler2DArray rings, int i, LayerHit hit) {
  float n = u_clip_rings[i], size = u_clip_size[i];
  vec2 q = hit.p / u_clip_texel[i];  // ring 0 texels from the camera
  float reach = log2(max(max(abs(q.x), abs(q.y)), 1.0) / (0.25 * size - 1.0));
  float level = clamp(max(max(u_terms[i] - termCount(i, hit), reach), u_clip_finest[i]), 0.0, n);
  float l = min(floor(level), n - 1.0);
  int k = int(l);
  float scale = exp2(-l);
  vec2 at = u_clip_offset[kRings * i + k] + q * scale;
  float fine = textureLod(rings, vec3(at / size, l), 0.0).r;
  int next = min(k + 1, int(n) - 1);
  vec2 at_next = u_clip_offset[kRings * i + next] + q * (0.5 * scale);
  float coarse = k + 1 < int(n) ? textureLod(rings, vec3(at_next / size, float(next)), 0.0).r
                                 : u_clip_constant[i];
  return mix(fine, coarse, level - l);
}
#endif

// T1 of slot i at `p` (metres from the camera): raised towards 1 as the weight of the layer's
// region falls (world/formations/region.h, MODEL.md section 11).
#ifdef REGIONS
float layerThreshold(int i, vec3 r, vec2 p) {
  float t1 = u_threshold[i];
  if (u_far[i].y > 0.0) {
    float cover = farApparentCover(u_far[i].x, u_far[i].y, r);  // world/formulas/far_deck.h
    vec2 cell = tableCell(cover, kFarCoverSteps);
    int k = (kFarCoverSteps + 1) * i + int(cell.x);
    t1 = mix(u_far_threshold[k], u_far_threshold[k + 1], cell.y);
  }
  vec2 q = regionAxes(p - u_region[i].xy, u_region[i].z, u_region[i].w);
  vec4 size = u_region_size[i];  // half sizes, edge band, transition band
  float w = regionWeightAt(q, size.xy, size.z, u_region_side[i], size.w);
  if (u_hole[i].x > 0.0) w *= bandRamp(length(p) - u_hole[i].x, u_hole[i].y);
  return regionThreshold(t1, w);
}
#else
float layerThreshold(int i, vec3 r, vec2 p) { return u_threshold[i]; }
#endif

// Slot i's surface under what lies in front of it: layers are composited nearest first, so
// `colour` holds the premultiplied sum of the surfaces in front and `transmittance` what they
// let through ("over" summed front to back, the same sum as back to front). `planes_sun` is the
// share of the sunlight the sky planes above it let through (MODEL.md section 16, "sky
// planes"; generated per slot with the casters above it, skyFragmentSource).
void composite(int i, vec3 r, LayerHit hit, float t1, float it, float planes_sun,
               inout vec3 colour, inout float transmittance) {
  float tr = translucence(it - t1, u_transition[i]);  // Gardner eq. 9
  if (tr >= 1.0) return;                                // clear here: nothing to add
  vec3 normal = vec3(0.0, 0.0, u_height[i] > 0.0 ? -1.0 : 1.0);  // turned towards the viewer
  float n_dot_l = dot(normal, u_to_sun);
  float highlight = 0.0;
#ifdef SPECULAR
  if (n_dot_l > 0.0) highlight = phongHighlight(normal, n_dot_l, u_to_sun, -normalize(r), u_shading[i].w);
#endif
  float diffuse = max(n_dot_l, 0.0);
#ifdef REGIONS
  // A far deck stands for heaps: lit as their mean, with no highlight (as the reference).
  if (u_far[i].y > 0.0) {
    diffuse = sphereDiffuse(dot(u_to_sun, -normalize(r)));
    highlight = 0.0;
  }
#endif
  vec3 surface = gardnerIntensity(u_shading[i], diffuse, highlight, it) * u_colour[i];
#if defined(PLANE_SHADOWS) || defined(SHADOWS)
  float sun = 1.0;
#ifdef PLANE_SHADOWS
  sun = planes_sun;
#endif
#ifdef SHADOWS
  // A plane under every heap takes the heaps' shadow where the sun's ray through it lands
  // (MODEL.md section 16, "planes under heaps").
  if (u_height[i] <= u_shadow_floor)
    sun *= mapSunlight(planeCrossing(vec3(hit.p, u_height[i]), -u_camera_z, u_to_sun));
#endif
  surface *= groundLight(sun);
#endif
#ifdef AIR
  surface = applyAir(surface, normalize(r), hit.distance);
#endif
  colour += transmittance * (1.0 - tr) * surface;
  transmittance *= tr;
}
