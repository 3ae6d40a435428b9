#include "renderer/gl/sky_shaders.h"

#include "renderer/gl/view_uniforms.h"
#include "world/formations/cloud_shadow.h"
#include "world/precipitation.h"
#include "world/textures/gardner_texture.h"

namespace nephele {
namespace {

// View (camera-relative: the shader knows only the camera's altitude), output, the air (fog and
// haze). The air is unlit and applied to each surface by its camera distance, which is exact
// under "over".
const char* kCommon = R"(
uniform vec3 u_right;    // image-plane basis, scaled by tan(vfov/2) * aspect
uniform vec3 u_up;       // scaled by tan(vfov/2)
uniform vec3 u_forward;
uniform vec2 u_viewport;
uniform float u_camera_z;
layout(location = 0) out vec4 o_colour;  // premultiplied colour, coverage
const float kFar = 1e30;

// The pixel a fragment stands for: its own, or in the per-pixel pass's sample pass, the
// full-resolution pixel its sample is taken at (MODEL.md section 15, "behind the veil").
#ifndef FRAG_XY
#define FRAG_XY gl_FragCoord.xy
#endif

// sin x for Gardner's sums: x in turns reduced to [-1/2, 1/2), folded to [-1/4, 1/4] by
// sin(pi - y) = sin y, then the Taylor polynomial to y^9, within 4e-6 of sin (below float's
// own error in x once |x| > 64). On llvmpipe it makes the frames that sum the sines about a
// seventh faster than the built-in sin (docs/ACCURACY.md, "Per-pixel sines").
float gardnerSin(float x) {
  float t = x * 0.15915494309189535;
  t -= floor(t + 0.5);
  t = abs(t) > 0.25 ? sign(t) * 0.5 - t : t;
  float y = 6.283185307179586 * t, y2 = y * y;
  return y * (1.0 + y2 * (-1.0 / 6.0 + y2 * (1.0 / 120.0 + y2 * (-1.0 / 5040.0 +
                                                                y2 * (1.0 / 362880.0)))));
}

vec3 viewRay() {
  vec2 ndc = 2.0 * FRAG_XY / u_viewport - 1.0;
  return u_right * ndc.x + u_up * ndc.y + u_forward;
}

#ifdef AIR
// The air between the eye and a surface (MODEL.md section 5): ground fog, the in-layer veil
// and distance haze; an absent one has zero extinction. world/sky.cpp's throughAir is the reference's twin.
uniform vec3 u_fog_slab;  // bottom, top, band of the ground fog, metres
uniform float u_fog_sigma;
uniform vec3 u_fog_colour;
uniform vec3 u_veil_slab;  // the in-layer veil's (MODEL.md section 5)
uniform float u_veil_sigma;
uniform vec3 u_veil_colour;
// Precipitation (MODEL.md section 17, precipitationMedia): up to kPrecipitationSlabs slabs
// (view_uniforms.h), sigma 0 for none.
uniform vec3 u_precip_slab[kPrecipitationSlabs];
uniform float u_precip_sigma[kPrecipitationSlabs];
uniform vec3 u_precip_colour[kPrecipitationSlabs];
// Shafts under heaps (MODEL.md section 17, RainShaft): the first u_shafts of kRainShafts, each
// its axis's X, Y from the camera, radius and top, metres; extinction and colour.
uniform vec4 u_shaft[kRainShafts];
uniform float u_shaft_sigma[kRainShafts];
uniform vec3 u_shaft_colour[kRainShafts];
uniform int u_shafts;
uniform float u_haze_sigma;   // at Z = 0, per metre
uniform float u_haze_height;  // scale height, metres
uniform vec3 u_haze_colour;   // the sky's horizon

// A slab's density (1 from bottom to top, linear to 0 over the band either side) and its
// integral from below it to height z (world/sky.cpp, fogDensity and fogColumn).
float slabDensity(vec3 slab, float z) {
  if (z >= slab.x && z <= slab.y) return 1.0;
  float out_by = z < slab.x ? slab.x - z : z - slab.y;
  return slab.z > 0.0 ? max(0.0, 1.0 - out_by / slab.z) : 0.0;
}
float slabColumn(vec3 slab, float z) {
  float b = slab.z, low = slab.x - b;
  if (!(z > low)) return 0.0;
  if (z <= slab.x) return (z - low) * (z - low) / (2.0 * b);
  if (z <= slab.y) return 0.5 * b + (z - slab.x);
  float u = min(z - slab.y, b);
  return 0.5 * b + (slab.y - slab.x) + u - (b > 0.0 ? u * u / (2.0 * b) : 0.0);
}

// The density-weighted length through a slab of the unit ray from the camera up to `distance`
// (world/sky.cpp's fogPathLength): level rays take the density half way.
float slabPath(vec3 slab, vec3 d, float distance) {
  float rise = distance * d.z;
  if (abs(rise) < 1e-3) return slabDensity(slab, u_camera_z + 0.5 * rise) * distance;
  return abs(slabColumn(slab, u_camera_z + rise) - slabColumn(slab, u_camera_z)) / abs(d.z);
}

// Shaft i's optical depth along the unit ray up to `distance` (world/sky.cpp's
// shaftOpticalDepth): the chord inside its cylinder and between the ground and its top, and the
// exact integral of its density, a cubic along the chord, about the chord's middle.
float shaftDepth(int i, vec3 d, float distance) {
  vec4 shaft = u_shaft[i];
  vec2 o = -shaft.xy, dh = d.xy;
  float r2 = shaft.z * shaft.z, a = dot(dh, dh), b = dot(o, dh);
  float t0 = 0.0, t1 = distance;
  if (a < 1e-8) {
    if (dot(o, o) >= r2) return 0.0;
  } else {
    float cross_od = o.x * dh.y - o.y * dh.x, quarter_delta = a * r2 - cross_od * cross_od;
    if (quarter_delta <= 0.0) return 0.0;
    float root = sqrt(quarter_delta);
    t0 = max(t0, (-b - root) / a);
    t1 = min(t1, (-b + root) / a);
  }
  if (d.z == 0.0) {
    if (u_camera_z < 0.0 || u_camera_z > shaft.w) return 0.0;
  } else {
    float at_ground = -u_camera_z / d.z, at_top = (shaft.w - u_camera_z) / d.z;
    t0 = max(t0, min(at_ground, at_top));
    t1 = min(t1, max(at_ground, at_top));
  }
  if (!(t1 > t0)) return 0.0;
  float m = 0.5 * (t0 + t1), h = 0.5 * (t1 - t0);
  vec2 q = o + m * dh;
  float g0 = 1.0 - dot(q, q) / r2, g1 = -2.0 * dot(q, dh) / r2, g2 = -a / r2;
  float fade = (1.0 - kShaftGroundShare) / shaft.w;
  float l0 = kShaftGroundShare + fade * (u_camera_z + m * d.z), l1 = fade * d.z;
  return u_shaft_sigma[i] * max(2.0 * h * g0 * l0 + (2.0 * h * h * h / 3.0) * (g2 * l0 + g1 * l1), 0.0);
}

// The haze's optical depth along the unit ray up to `distance`: sigma0 H (e^-a - e^-(a+x)) / dz,
// a = z0 / H, x = s dz / H, or its series near x = 0 (hazeOpticalDepth).
float hazeDepth(vec3 d, float distance) {
  float s = min(distance, 1e9), h = u_haze_height;
  float a = u_camera_z / h, x = s * d.z / h;
  if (abs(x) < 1e-2) return u_haze_sigma * s * exp(-a) * (1.0 - x / 2.0 + x * x / 6.0);
  return u_haze_sigma * h / d.z * (exp(-a) - exp(-max(a + x, -50.0)));
}

vec3 applyAir(vec3 colour, vec3 d, float distance) {
  float tau_fog = u_fog_sigma > 0.0 ? min(u_fog_sigma * slabPath(u_fog_slab, d, distance), 1e3)
                                    : 0.0;
  float tau_veil =
      u_veil_sigma > 0.0 ? min(u_veil_sigma * slabPath(u_veil_slab, d, distance), 1e3) : 0.0;
  float tau_haze = min(hazeDepth(d, distance), 1e3);
  float tau = tau_fog + tau_veil + tau_haze;
  vec3 weighted = tau_fog * u_fog_colour + tau_veil * u_veil_colour + tau_haze * u_haze_colour;
  for (int i = 0; i < kPrecipitationSlabs; ++i)
    if (u_precip_sigma[i] > 0.0) {
      float tau_p = min(u_precip_sigma[i] * slabPath(u_precip_slab[i], d, distance), 1e3);
      tau += tau_p;
      weighted += tau_p * u_precip_colour[i];
    }
  for (int i = 0; i < u_shafts; ++i) {
    float tau_s = min(shaftDepth(i, d, distance), 1e3);
    tau += tau_s;
    weighted += tau_s * u_shaft_colour[i];
  }
  if (!(tau > 0.0)) return colour;
  return mix(weighted / tau, colour, exp(-tau));
}

// The air at the end of an endless path through it (the ground at the horizon): each medium
// present at its cap, as applyAir weighs them there (the veil is present only around the eye).
vec3 airAtHorizon() {
  float f = u_fog_sigma > 0.0 ? 1.0 : 0.0, v = u_veil_sigma > 0.0 ? 1.0 : 0.0;
  float h = u_haze_sigma > 0.0 ? 1.0 : 0.0;
  float n = f + v + h;
  vec3 sum = f * u_fog_colour + v * u_veil_colour + h * u_haze_colour;
  for (int i = 0; i < kPrecipitationSlabs; ++i)  // those that reach the ground
    if (u_precip_sigma[i] > 0.0 && u_precip_slab[i].x <= 0.0) {
      n += 1.0;
      sum += u_precip_colour[i];
    }
  return sum / max(n, 1.0);
}
#else
vec3 applyAir(vec3 colour, vec3 d, float distance) { return colour; }
#endif

#ifdef TARGETS
// Opaque targets drawn first: their fogged colour and their distance along the unit ray
// (1e30 where there is none), read at this pixel.
layout(binding = 14) uniform sampler2D u_target_colour;
layout(binding = 15) uniform sampler2D u_target_distance;
float targetDistance() { return texelFetch(u_target_distance, ivec2(FRAG_XY), 0).r; }
vec3 targetColour() { return texelFetch(u_target_colour, ivec2(FRAG_XY), 0).rgb; }
#endif

// Gardner eq. 8 (MODEL.md section 3) from its terms; shading = (a, t, s, e).
float gardnerIntensity(vec4 shading, float diffuse, float highlight, float it) {
  float a = shading.x, t = shading.y, s = shading.z;
  return (1.0 - a) * ((1.0 - t) * ((1.0 - s) * diffuse + s * highlight) + t * it) + a;
}

// Gardner eq. 9 and 11 (MODEL.md section 4): translucence TR for the texture's excess over
// the threshold; D = 0 is a hard threshold.
float translucence(float excess, float d) {
  return d <= 0.0 ? (excess <= 0.0 ? 1.0 : 0.0) : clamp(1.0 - excess / d, 0.0, 1.0);
}

// Gardner terms a pixel resolves (MODEL.md section 2), fractional where one fades, for a
// footprint in periods: term j (1-based) resolves while 2^j footprint <= 1/2
// (GardnerTexture::termCountForFootprint on the CPU).
float resolvedTerms(float footprint, float terms) {
#if defined(FILTER_NONE)
  return terms;
#else
  float highest = log2(0.5 / max(footprint, 1e-30));
#if defined(FILTER_CUT)
  return clamp(floor(highest), 0.0, terms);
#else
  return clamp(highest - 1.0, 0.0, terms);  // fade over the octave below
#endif
#endif
}

// Distance in metres along r (any length) to the first opaque surface: the ground plane
// (MODEL.md section 5) or a target; kFar where the ray reaches the sky.
float opaqueDistance(vec3 r) {
  float distance = r.z < 0.0 ? u_camera_z * (length(r) / -r.z) : kFar;
#ifdef TARGETS
  distance = min(distance, targetDistance());
#endif
  return distance;
}

// The altitude band a cloud pass draws (docs/MODEL.md, "Compositing order"): a surface at
// height dz above the camera belongs to this pass when u_band.x <= dz < u_band.y or
// u_band.z <= dz < u_band.w. Layers are horizontal planes, so along every ray the surfaces
// between two layers are exactly those between their altitudes.
uniform vec4 u_band = vec4(-1e38, 1e38, 0.0, 0.0);
bool inBand(float dz) {
  return (dz >= u_band.x && dz < u_band.y) || (dz >= u_band.z && dz < u_band.w);
}

#ifdef SHADOWS
// The share of the sunlight reaching the ground (MODEL.md section 16, ShadowMap) at `ground`
// (metres from the camera's ground point): the map is u_shadow_half * 2 metres a side about
// u_shadow_centre; it fades to 1 over its outer twentieth, where the ground lies beyond its
// casters' range. Below u_shadow_floor (from the camera) every caster lies above.
layout(binding = 11) uniform sampler2D u_shadow_map;
uniform vec2 u_shadow_centre;
uniform float u_shadow_half;
uniform float u_shadow_floor;
float mapSunlight(vec2 ground) {
  vec2 uv = (ground - u_shadow_centre) / (2.0 * u_shadow_half) + 0.5;
  float edge = 2.0 * max(abs(uv.x - 0.5), abs(uv.y - 0.5));
  return mix(texture(u_shadow_map, uv).r, 1.0, smoothstep(0.9, 1.0, edge));
}
#endif

#ifdef BACKGROUND
uniform vec3 u_zenith;
uniform vec3 u_horizon;
uniform vec3 u_ground;

uniform float u_horizon_slope;  // |gradient of r.z| per pixel

// The sky planes' share of the sunlight at this pixel's ground point (planesSunlight), set by
// main before background() where planes cast shadows.
float g_planes_sun = 1.0;
// The share of the sunlight reaching the ground point along unit d.
float groundSunlight(vec3 d) {
  float sun = g_planes_sun;
#ifdef SHADOWS
  sun *= mapSunlight(d.xy * (u_camera_z / -d.z));
#endif
  return sun;
}
vec3 groundColour(vec3 d) {
#if defined(SHADOWS) || defined(PLANE_SHADOWS)
  return u_ground * (kGroundSkyShare + (1.0 - kGroundSkyShare) * groundSunlight(d));
#else
  return u_ground;
#endif
}

#ifdef SEA
// The sea (MODEL.md section 18); world/sea.cpp is the reference's twin, function by function.
// The surface's sines, longest first: wave vector (rad/m), amplitude, and the phase at the
// camera's ground point now (mod 2 pi, in double on the CPU).
uniform vec4 u_wave[kSeaWaves];
// Each one's phase modulation: its wave vector, and its phase at the camera's ground point.
uniform vec3 u_wave_wobble[kSeaWaves];
uniform int u_waves;
// Cox-Munk's slope variance, the drawn sines' slope variance, the whitecap fraction, the
// pixel's angle in radians.
uniform vec4 u_sea;
uniform float u_foam_steepness;  // SeaSurface::foamSteepness
uniform vec3 u_sea_body;  // waterBodyColour, times the sun's colour
uniform vec3 u_sea_sun;   // unit, towards the sun
uniform vec3 u_sun_colour;
// What the sea mirrors (the probe: the scene from the sea below the camera); a direction r
// is at ((r . right, r . up) / (r . forward) + 1) / 2 in it.
layout(binding = 6) uniform sampler2D u_sea_probe;
uniform vec3 u_probe_right;
uniform vec3 u_probe_up;
uniform vec3 u_probe_forward;
const float kSeaResolvedShare = 0.8;
const float kFoamReflectance = 0.22;

float fresnelWater(float cos_incidence) {
  float c = clamp(cos_incidence, 0.0, 1.0), n = 1.34;
  float g = sqrt(n * n - 1.0 + c * c);
  float a = (g - c) / (g + c), b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
  return 0.5 * a * a * (1.0 + b * b);
}

float foamShare(float w, float foam_steepness, float steepness, float var_total,
                float var_unresolved) {
  if (!(w > 0.0)) return 0.0;
  if (w >= 1.0) return 1.0;
  float resolved = var_total > 0.0 ? clamp(1.0 - var_unresolved / var_total, 0.0, 1.0) : 0.0;
  float edge = sqrt(max(var_unresolved, 1e-4 * var_total + 1e-12));
  float crest = 1.0 / (1.0 + exp(-1.702 * (steepness - foam_steepness) / edge));
  return (1.0 - resolved) * w + resolved * crest;
}

float glintRadiance(vec3 d, vec3 n, float slope_var) {
  vec3 v = -d, sun = u_sea_sun;
  float mu_v = dot(v, n), mu_s = dot(sun, n);
  if (!(mu_v > 0.0) || !(mu_s > 0.0)) return 0.0;
  vec3 h = normalize(v + sun);
  float mu_n = dot(h, n);
  if (!(mu_n > 0.0)) return 0.0;
  float mu_n2 = mu_n * mu_n, tan2 = (1.0 - mu_n2) / mu_n2;
  return fresnelWater(dot(v, h)) * exp(-tan2 / slope_var) /
         (4.0 * slope_var * max(mu_v, 1e-2) * mu_n2 * mu_n2);
}

vec3 probeRadiance(vec3 r) {
  vec2 ndc = vec2(dot(r, u_probe_right), dot(r, u_probe_up)) / max(dot(r, u_probe_forward), 1e-6);
  return texture(u_sea_probe, clamp(0.5 * ndc + 0.5, 0.0, 1.0)).rgb;
}

// The sea's radiance along unit d (d.z < 0), before the air.
vec3 seaColour(vec3 d) {
  float distance = u_camera_z / -d.z;
  vec2 p = d.xy * distance;
  float footprint = distance * u_sea.w / sqrt(max(abs(d.z), 1e-4));
  float resolved_slope = 0.0;
  vec2 slope = vec2(0.0);
  for (int i = 0; i < u_waves; ++i) {
    vec4 w = u_wave[i];
    float k = length(w.xy);
    float weight = clamp(6.283185307179586 / k / (4.0 * footprint) - 1.0, 0.0, 1.0);
    if (weight <= 0.0) break;
    vec3 m = u_wave_wobble[i];
    float wobble = dot(m.xy, p) + m.z;
    float phase = dot(w.xy, p) + w.w + kWaveModulation * gardnerSin(wobble);
    slope -= (weight * w.z * gardnerSin(phase)) *
             (w.xy + kWaveModulation * gardnerSin(wobble + 1.5707963267948966) * m.xy);
    resolved_slope += 0.5 * weight * weight * w.z * w.z * k * k;
  }
  float slope_var = max(u_sea.x - resolved_slope, (1.0 - kSeaResolvedShare) * u_sea.x);
  vec3 n = normalize(vec3(-slope, 1.0));
  float cos_i = clamp(-dot(d, n), 0.0, 1.0);
  vec3 r = d + 2.0 * cos_i * n;
  r.z = max(r.z, 0.01);
  r = normalize(r);
  float foam = foamShare(u_sea.z, u_foam_steepness, dot(slope, slope), u_sea.y,
                         max(u_sea.y - resolved_slope, 0.0));
  float fresnel = fresnelWater(cos_i);
  float sun = groundSunlight(d);
  float diffuse = max(u_sea_sun.z, 0.0) * (kGroundSkyShare + (1.0 - kGroundSkyShare) * sun);
  vec3 colour = diffuse * ((1.0 - foam) * (1.0 - fresnel) * u_sea_body +
                           foam * kFoamReflectance * u_sun_colour);
  if (u_sea_sun.z > 0.0 && sun > 0.0)
    colour += (1.0 - foam) * sun * glintRadiance(d, n, slope_var) * u_sun_colour;
  return colour + (1.0 - foam) * fresnel * probeRadiance(r);
}
#endif

vec3 background(vec3 r) {
  vec3 d = normalize(r);
  // The ground's share of the pixel: r.z is linear across the image, so the horizon is a
  // straight edge and its box-filtered coverage is exact.
  float ground = clamp(0.5 - r.z / u_horizon_slope, 0.0, 1.0);
  vec3 sky = u_horizon + (u_zenith - u_horizon) * sqrt(max(d.z, 0.0));  // MODEL.md section 5
#ifdef SEA
  vec3 below = d.z < 0.0 ? seaColour(d) : u_horizon;
#else
  vec3 below = d.z < 0.0 ? groundColour(d) : u_ground;
#endif
#ifdef AIR
  // Each part carries its own air. The ground seen at the horizon lies behind an endless
  // stretch of air (fog and haze touch the ground), so there it is the air's colour.
  vec3 aired_ground = d.z < 0.0 ? applyAir(below, d, u_camera_z / -d.z) : airAtHorizon();
  return mix(applyAir(sky, d, kFar), aired_ground, ground);
#else
  return mix(sky, below, ground);
#endif
}
#endif
)";

const char* kLayers = R"(
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
uniform float u_far_threshold[kSlots * 17];  // its T1 at cover 0, 1/16, ..., 1
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
      max(length(hit.dpdx * u_inv_period[i]), length(hit.dpdy * u_inv_period[i])), u_terms[i]);
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
  float t = u_k[i] * max(sx, 0.0) * max(sy, 0.0);
  float fraction = count - float(whole);
  if (fraction > 0.0) {
    addTerm(i, whole, p, sx, sy);
    t = mix(t, u_k[i] * max(sx, 0.0) * max(sy, 0.0), fraction);
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

float clipmapValue(sampler2DArray rings, int i, LayerHit hit) {
  float n = u_clip_rings[i], size = u_clip_size[i];
  vec2 q = hit.p / u_clip_texel[i];  // ring 0 texels from the camera
  float reach = log2(max(max(abs(q.x), abs(q.y)), 1.0) / (0.25 * size - 1.0));
  float level = clamp(max(u_terms[i] - termCount(i, hit), reach), 0.0, n);
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
float regionRamp(float x, float width) {
  float u = clamp(x / max(width, 1.0e-3), 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
}
// A far deck stands for rounded heaps: the mean of max(0, N.L) over a Lambertian sphere's
// visible disc at phase angle alpha, 2/3 (sin alpha + (pi - alpha) cos alpha) / pi.
float sphereDiffuse(float cos_alpha) {
  float alpha = acos(clamp(cos_alpha, -1.0, 1.0));
  return (2.0 / 3.0) * (sin(alpha) + (3.14159265 - alpha) * cos(alpha)) / 3.14159265;
}
float layerThreshold(int i, vec3 r, vec2 p) {
  float t1 = u_threshold[i];
  if (u_far[i].y > 0.0) {
    float cot_e = length(r.xy) / max(abs(r.z), 1e-9 * length(r));
    float cover = 1.0 - pow(1.0 - min(u_far[i].x, 1.0), 1.0 + u_far[i].y * cot_e);
    float x = clamp(cover, 0.0, 1.0) * 16.0;
    int k = min(int(x), 15);
    t1 = mix(u_far_threshold[17 * i + k], u_far_threshold[17 * i + k + 1], x - float(k));
  }
  vec2 d = p - u_region[i].xy;
  vec2 q = vec2(d.x * u_region[i].z - d.y * u_region[i].w, d.x * u_region[i].w + d.y * u_region[i].z);
  vec4 size = u_region_size[i];
  float w = regionRamp(size.x - abs(q.x), size.z) * regionRamp(size.y - abs(q.y), size.z);
  if (u_region_side[i] != 0.0) w *= regionRamp(u_region_side[i] * q.x + 0.5 * size.w, size.w);
  if (u_hole[i].x > 0.0) w *= regionRamp(length(p) - u_hole[i].x, u_hole[i].y);
  return t1 >= 1.0 ? t1 : t1 + (1.0 - w) * (1.0 - t1);
}
#else
float layerThreshold(int i, vec3 r, vec2 p) { return u_threshold[i]; }
#endif

#ifdef PLANE_SHADOWS
// The share of the sunlight the sky planes above a point let through (MODEL.md section 16,
// "sky planes"), the point `hit` on the plane `height` metres above the camera; generated
// with the casting slots (skyFragmentSource).
float planesSunlight(LayerHit hit, float height);
#endif

// Slot i's surface under what lies in front of it: layers are composited nearest first, so
// `colour` holds the premultiplied sum of the surfaces in front and `transmittance` what they
// let through ("over" summed front to back, the same sum as back to front).
void composite(int i, vec3 r, LayerHit hit, float t1, float it, inout vec3 colour,
               inout float transmittance) {
  float tr = translucence(it - t1, u_transition[i]);  // Gardner eq. 9
  if (tr >= 1.0) return;                                // clear here: nothing to add
  vec3 normal = vec3(0.0, 0.0, u_height[i] > 0.0 ? -1.0 : 1.0);  // turned towards the viewer
  float n_dot_l = dot(normal, u_to_sun);
  float highlight = 0.0;
#ifdef SPECULAR
  if (n_dot_l > 0.0) {
    vec3 reflected = 2.0 * n_dot_l * normal - u_to_sun;
    highlight = pow(max(dot(reflected, -normalize(r)), 0.0), u_shading[i].w);
  }
#endif
  float diffuse = max(n_dot_l, 0.0);
#ifdef REGIONS
  if (u_far[i].y > 0.0) diffuse = sphereDiffuse(dot(u_to_sun, -normalize(r)));
#endif
  vec3 surface = gardnerIntensity(u_shading[i], diffuse, highlight, it) * u_colour[i];
#if defined(PLANE_SHADOWS) || defined(SHADOWS)
  float sun = 1.0;
#ifdef PLANE_SHADOWS
  sun = planesSunlight(hit, u_height[i]);
#endif
#ifdef SHADOWS
  // A plane under every heap takes the heaps' shadow where the sun's ray through it lands
  // (MODEL.md section 16, "planes under heaps").
  if (u_height[i] <= u_shadow_floor)
    sun *= mapSunlight(hit.p - ((u_height[i] + u_camera_z) / u_to_sun.z) * u_to_sun.xy);
#endif
  surface *= kGroundSkyShare + (1.0 - kGroundSkyShare) * sun;
#endif
#ifdef AIR
  surface = applyAir(surface, normalize(r), hit.distance);
#endif
  colour += transmittance * (1.0 - tr) * surface;
  transmittance *= tr;
}
)";

// The expression for slot `slot`'s texture value at `hit`.
std::string slotValue(int slot, LayerKind kind, const std::string& hit) {
  const std::string i = std::to_string(slot);
  switch (kind) {
    case LayerKind::kBakedGardner:
      return "bakedValue(u_table" + i + ", " + i + ", " + hit + ")";
    case LayerKind::kTable:
      return "tableValue(u_table" + i + ", " + i + ", " + hit + ")";
    case LayerKind::kProceduralGardner:
      return "proceduralValue(" + i + ", " + hit + ")";
    case LayerKind::kClipmapGardner:
      return "clipmapValue(u_table" + i + ", " + i + ", " + hit + ")";
  }
  return "0.0";
}

// A casting slot's share of the sunlight at a point below it: its translucence (Gardner eq. 9)
// where the sun's ray through the point crosses its plane (MODEL.md section 16, "sky planes").
// Its threshold takes the sun's direction as the view's, for a far deck's cover. The term
// filter reads the texture over the receiving pixel's footprint or, where wider, the shadow's
// penumbra: the sun's disc, 0.0093 radians across, seen over the distance to the plane.
std::string casterFunction(int caster, int slot, LayerKind kind) {
  const std::string c = std::to_string(caster), i = std::to_string(slot);
  return "float casterSunlight" + c + "(LayerHit hit, float height) {\n" +
         "  float rise = u_height[" + i + "] - height;\n" + "  if (!(rise > 0.0)) return 1.0;\n" +
         "  hit.p += (rise / u_to_sun.z) * u_to_sun.xy;\n" + "  float t1 = layerThreshold(" + i +
         ", u_to_sun, hit.p);\n" + "  if (t1 >= 1.0) return 1.0;\n" +
         "  float penumbra = 0.0093 * rise / u_to_sun.z;\n" +
         "  if (length(hit.dpdx) < penumbra) hit.dpdx = vec2(penumbra, 0.0);\n" +
         "  if (length(hit.dpdy) < penumbra) hit.dpdy = vec2(0.0, penumbra);\n" +
         "  return translucence(" + slotValue(slot, kind, "hit") + " - t1, u_transition[" + i +
         "]);\n}\n";
}

std::string slotStatement(int slot, LayerKind kind) {
  const std::string i = std::to_string(slot);
  const std::string value = slotValue(slot, kind, "hit");
  // Behind a surface that is opaque to within 1/1024 nothing more is evaluated (what the
  // layers there could add is below half an 8-bit step): a full deck costs its nearest plane.
  // Nor is the texture where the threshold is 1 or more, since T <= 1 (MODEL.md section 2)
  // leaves the layer clear there: a far deck's hole around the camera, where the heaps stand,
  // costs its threshold only.
  return "    if (transmittance > kClear) { LayerHit hit = hitLayer(" + i +
         ", r); float t1 = inFront(hit.distance) ? layerThreshold(" + i +
         ", r, hit.p) : 1.0; if (t1 < 1.0) composite(" + i + ", r, hit, t1, " + value +
         ", colour, transmittance); }\n";
}

// kCommon after the constants it takes from C++.
std::string commonSource() {
  return "const int kPrecipitationSlabs = " + std::to_string(kPrecipitationSlabs) +
         ";\nconst int kRainShafts = " + std::to_string(kMaxRainShafts) +
         ";\nconst float kShaftGroundShare = " + std::to_string(kShaftGroundShare) + ";\n" +
         kCommon;
}

}  // namespace

std::string SkyPassLayout::key() const {
  std::string k = background ? "bg/" : "--/";
  for (LayerKind kind : above) k += char('a' + int(kind));
  k += '/';
  for (LayerKind kind : below) k += char('a' + int(kind));
  k += '/';
  k += char('0' + int(term_filter));
  k += air ? 'f' : '-';
  k += specular ? 's' : '-';
  k += targets ? 't' : '-';
  k += regions ? 'r' : '-';
  k += shadows ? 'h' : '-';
  k += sea ? 'w' : '-';
  k += '/';
  for (LayerKind kind : casters) k += char('a' + int(kind));
  return k;
}

std::string viewShaderSource() {
  return commonSource();
}

std::string clipmapBakeSource() {
  std::string s = "#version 450 core\n#define PROCEDURAL\n";
  s += "const int kComponents = " + std::to_string(GardnerTextureParams::kComponents) + ";\n";
  s += "const int kSlots = 1;\n";
  s += commonSource();
  s += kLayers;
  // Slot 0's phases are taken at the corner of the ring's window (lattice index `first` in
  // absolute terms); the fragment at storage texel s holds the window's texel (s - first) mod N.
  s += R"(
uniform ivec2 u_bake_first;   // the window's first lattice index, modulo N
uniform int u_bake_size;      // N
uniform vec2 u_bake_texel;    // metres per texel of this ring
uniform float u_bake_terms;   // n - l
void main() {
  ivec2 rel = (ivec2(gl_FragCoord.xy) - u_bake_first + u_bake_size) % u_bake_size;
  o_colour = vec4(truncatedValue(0, (vec2(rel) + 0.5) * u_bake_texel, u_bake_terms));
}
)";
  return s;
}

std::string polygonVertexSource() {
  return R"(#version 450 core
uniform vec2 u_polygon[8];  // convex polygon in normalised device coordinates, a triangle fan
void main() { gl_Position = vec4(u_polygon[gl_VertexID], 0.0, 1.0); }
)";
}

std::string skyFragmentSource(const SkyPassLayout& layout) {
  std::string s = "#version 450 core\n";
  if (layout.air) s += "#define AIR\n";
  if (layout.background) s += "#define BACKGROUND\n";
  if (layout.specular) s += "#define SPECULAR\n";
  if (layout.targets) s += "#define TARGETS\n";
  if (layout.regions) s += "#define REGIONS\n";
  if (layout.shadows) s += "#define SHADOWS\n";
  if (!layout.casters.empty()) s += "#define PLANE_SHADOWS\n";
  if (layout.sea)
    s += "#define SEA\nconst int kSeaWaves = " + std::to_string(kMaxSeaWaves) +
         ";\nconst float kWaveModulation = " + std::to_string(kWaveModulation) + ";\n";
  if (layout.shadows || !layout.casters.empty() || layout.sea)
    s += "const float kGroundSkyShare = " + std::to_string(kGroundSkyShare) + ";\n";
  if (layout.term_filter == TermFilter::kCut) s += "#define FILTER_CUT\n";
  if (layout.term_filter == TermFilter::kNone) s += "#define FILTER_NONE\n";
  bool procedural = false, clipmap = false;
  // Slots 0 .. slots() - 1 are drawn; the casters follow them.
  for (const auto* side : {&layout.above, &layout.below, &layout.casters})
    for (LayerKind kind : *side) {
      procedural |= kind == LayerKind::kProceduralGardner;
      clipmap |= kind == LayerKind::kClipmapGardner;
    }
  if (procedural) s += "#define PROCEDURAL\n";
  if (clipmap) s += "#define CLIPMAP\n";
  s += "const int kComponents = " + std::to_string(GardnerTextureParams::kComponents) + ";\n";
  const int slots = layout.slots() + int(layout.casters.size());
  s += "const int kSlots = " + std::to_string(std::max(slots, 1)) + ";\n";
  s += commonSource();
  if (slots > 0) s += kLayers;
  // One sampler uniform per sampled slot: llvmpipe samples a sampler-array element far more
  // slowly.
  int slot = 0;
  for (const auto* side : {&layout.above, &layout.below, &layout.casters})
    for (LayerKind kind : *side) {
      const std::string name = " u_table" + std::to_string(slot++) + ";\n";
      if (kind == LayerKind::kClipmapGardner) s += "uniform sampler2DArray" + name;
      if (kind == LayerKind::kBakedGardner || kind == LayerKind::kTable)
        s += "uniform sampler2D" + name;
    }
  if (!layout.casters.empty()) {
    std::string product = "1.0";
    for (std::size_t c = 0; c < layout.casters.size(); ++c) {
      s += casterFunction(int(c), layout.slots() + int(c), layout.casters[c]);
      product += " * casterSunlight" + std::to_string(c) + "(hit, height)";
    }
    s += "float planesSunlight(LayerHit hit, float height) { return " + product + "; }\n";
  }

  s += "const float kClear = 1.0 / 1024.0;\n";
  s += "void main() {\n  vec3 r = viewRay();\n";
  if (layout.targets) {
    // Layers behind a target are hidden; the target replaces the background.
    s += "  float target_distance = targetDistance();\n";
    s += "#define inFront(d) ((d) < target_distance)\n";
  } else {
    s += "#define inFront(d) true\n";
  }
  s += "  vec3 colour = vec3(0.0);\n  float transmittance = 1.0;\n";
  // Slots are listed farthest first on each side: emitted in reverse, nearest first.
  const int above = int(layout.above.size());
  if (above > 0) {
    s += "  if (r.z > 0.0) {\n";
    for (int slot = above - 1; slot >= 0; --slot)
      s += slotStatement(slot, layout.above[std::size_t(slot)]);
    s += "  }\n";
  }
  if (!layout.below.empty()) {
    s += "  if (r.z < 0.0) {\n";
    for (int k = int(layout.below.size()) - 1; k >= 0; --k)
      s += slotStatement(above + k, layout.below[std::size_t(k)]);
    s += "  }\n";
  }
  if (layout.background) {
    if (!layout.casters.empty())  // the ground, where the layers in front let it show
      s += "  if (r.z < 0.0 && transmittance > kClear) g_planes_sun = "
           "planesSunlight(hitPlane(-u_camera_z, r), -u_camera_z);\n";
    s += "  vec3 behind = background(r);\n";
    if (layout.targets) s += "  if (target_distance < kFar) behind = targetColour();\n";
    s += "  colour += transmittance * behind;\n";
  }
  s += "  o_colour = vec4(colour, 1.0 - transmittance);\n}\n";
  return s;
}

}  // namespace nephele
