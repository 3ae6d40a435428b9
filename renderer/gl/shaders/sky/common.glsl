
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
// A stage compiles the media its scene holds, AIR_FOG to AIR_SHAFTS (airDefines).
// The air between the eye and a surface (MODEL.md section 5): ground fog, the in-layer veil
// and distance haze; an absent one has zero extinction. Each medium's optical depth and their
// mixing are the shared formulas' (world/formulas/air.h, pasted ahead of this file), as in
// world/sky.cpp's throughAir; what stays here is which media there are (uniforms, sigma 0 for
// none, where throughAir takes optionals and spans) and the endless path, kFar here and
// +infinity there (fogPathLength's guards).
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

vec3 applyAir(vec3 colour, vec3 d, float distance) {
  float z = u_camera_z;
  vec4 air = vec4(0.0);
#ifdef AIR_FOG
  float tau_fog = u_fog_sigma > 0.0 ? u_fog_sigma * slabPath(u_fog_slab, z, d.z, distance) : 0.0;
  air = withMedium(air, tau_fog, u_fog_colour);
#endif
#ifdef AIR_VEIL
  float tau_veil =
      u_veil_sigma > 0.0 ? u_veil_sigma * slabPath(u_veil_slab, z, d.z, distance) : 0.0;
  air = withMedium(air, tau_veil, u_veil_colour);
#endif
#ifdef AIR_HAZE
  air = withMedium(air, hazeDepth(u_haze_sigma, u_haze_height, z, d.z, distance), u_haze_colour);
#endif
#ifdef AIR_SLABS
  for (int i = 0; i < kPrecipitationSlabs; ++i)
    if (u_precip_sigma[i] > 0.0)
      air = withMedium(air, u_precip_sigma[i] * slabPath(u_precip_slab[i], z, d.z, distance),
                       u_precip_colour[i]);
#endif
#ifdef AIR_SHAFTS
  for (int i = 0; i < u_shafts; ++i)
    air = withMedium(air, shaftDepth(u_shaft[i], u_shaft_sigma[i], z, d, distance),
                     u_shaft_colour[i]);
#endif
  return airOver(colour, air.xyz, air.w);
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

// The stage's removal of terms above the pixel's frequency, for resolvedTerms
// (world/formulas/texture.h).
#if defined(FILTER_NONE)
const int kTermFilter = kTermAll;
#elif defined(FILTER_CUT)
const int kTermFilter = kTermCut;
#else
const int kTermFilter = kTermFade;
#endif

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
  sun *= mapSunlight(planeCrossing(vec3(0.0, 0.0, u_camera_z), 0.0, d));
#endif
  return sun;
}
vec3 groundColour(vec3 d) {
#if defined(SHADOWS) || defined(PLANE_SHADOWS)
  return u_ground * groundLight(groundSunlight(d));
#else
  return u_ground;
#endif
}

#ifdef SEA
// The sea (MODEL.md section 18): its optics, each sine's weight, slope and variance are
// world/formulas/sea.h's, as in world/sea.cpp; the sum over the sines is SeaSurface::sample's
// with gardnerSin in place of sin and cos (docs/ACCURACY.md, "Per-pixel sines"), the phases
// camera-relative (MODEL.md section 2's precision rule).
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

vec3 probeRadiance(vec3 r) {
  vec2 ndc = vec2(dot(r, u_probe_right), dot(r, u_probe_up)) / max(dot(r, u_probe_forward), 1e-6);
  return texture(u_sea_probe, clamp(0.5 * ndc + 0.5, 0.0, 1.0)).rgb;
}

// The sea's radiance along unit d (d.z < 0), before the air.
vec3 seaColour(vec3 d) {
  float distance = u_camera_z / -d.z;
  vec2 p = d.xy * distance;
  float footprint = seaFootprint(distance, d.z, u_sea.w);
  float resolved_slope = 0.0;
  vec2 slope = vec2(0.0);
  for (int i = 0; i < u_waves; ++i) {
    vec4 w = u_wave[i];
    float k = length(w.xy);
    float weight = waveResolved(6.283185307179586 / k, footprint);
    if (weight <= 0.0) break;
    vec3 m = u_wave_wobble[i];
    float wobble = dot(m.xy, p) + m.z;
    float phase = dot(w.xy, p) + w.w + kWaveModulation * gardnerSin(wobble);
    slope -= waveSlope(weight, w.z, gardnerSin(phase), w.xy, kWaveModulation,
                       gardnerSin(wobble + 1.5707963267948966), m.xy);
    resolved_slope += waveHeightVariance(weight, w.z) * k * k;
  }
  float slope_var = unresolvedSlopeVariance(u_sea.x, resolved_slope);
  vec3 n = seaNormal(slope);
  float cos_i = seaIncidence(d, n);
  vec3 r = mirroredRay(d, n, cos_i);
  float foam = foamShare(u_sea.z, u_foam_steepness, dot(slope, slope), u_sea.y,
                         max(u_sea.y - resolved_slope, 0.0));
  float fresnel = fresnelWater(cos_i, 1.34);
  float sun = groundSunlight(d);
  float diffuse = max(u_sea_sun.z, 0.0) * groundLight(sun);
  vec3 colour = seaBodyAndFoam(diffuse, foam, fresnel, u_sea_body, u_sun_colour);
  if (u_sea_sun.z > 0.0 && sun > 0.0)
    colour += (1.0 - foam) * sun * glintRadiance(d, u_sea_sun, n, slope_var) * u_sun_colour;
  return colour + (1.0 - foam) * fresnel * probeRadiance(r);
}
#endif

vec3 background(vec3 r) {
  vec3 d = normalize(r);
  // The ground's share of the pixel: r.z is linear across the image, so the horizon is a
  // straight edge and its box-filtered coverage is exact.
  float ground = clamp(0.5 - r.z / u_horizon_slope, 0.0, 1.0);
  vec3 sky = skyGradient(u_horizon, u_zenith, d.z);
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
