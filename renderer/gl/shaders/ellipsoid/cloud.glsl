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
// lies behind the eye (world/formulas/ellipsoid.h).
float hitEllipsoid(int i, vec3 r) {
  vec3 w = toUnit(i, r), o = record(i, 3).xyz;
  float quarter_delta = quarterDelta(o, w);
  if (quarter_delta <= 0.0) return -1.0;
  vec2 s = unitSphereRoots(o, w, record(i, 3).w, quarter_delta);
  return min(s.x, s.y);
}

#ifdef SPOTLIGHT
layout(binding = 10) uniform sampler2D u_spotlight;  // 1 - rho^2 over [-1, 1]^2
#endif

// The limb function g (MODEL.md section 4) for view direction d.
float limbG(int i, vec3 d) {
#ifdef SPOTLIGHT
  // Elinas: a radial texture projected from the eye along the cone's axis.
  vec3 a = record(i, 4).xyz;
  float along = dot(d, a);
  if (along <= 0.0) return 0.0;
  vec3 q = d / along - a;
  vec2 st = vec2(dot(record(i, 8).xyz, q), dot(record(i, 9).xyz, q));
  return textureLod(u_spotlight, 0.5 + 0.5 * st, 0.0).r;
#else
  return limbFunction(d, record(i, 4).xyz, record(i, 5).xyz, record(i, 6).xyz, record(i, 7).xyz);
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
      max(length(dpdx), length(dpdy)) * max(u_inv_period.x, u_inv_period.y), u_terms,
      kTermFilter);
  int whole = int(count);
  float sx = u_t0, sy = u_t0;
  for (int j = 0; j < whole; ++j) addSolidTerm(j, p, sx, sy);
  float t = textureFromSums(sx, sy, u_k);
  float fraction = count - float(whole);
  if (fraction > 0.0) {
    addSolidTerm(whole, p, sx, sy);
    t = mix(t, textureFromSums(sx, sy, u_k), fraction);
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
  return textureFromSums(s.x, s.y, u_k);
}
#else
// A periodic 3D texture: Perlin noise with ordinary mipmaps.
layout(binding = 9) uniform sampler3D u_volume;
float solidValue(vec3 p, vec3 dpdx, vec3 dpdy) {
  return textureGrad(u_volume, u_tex_origin + p * u_inv_period, dpdx * u_inv_period,
                     dpdy * u_inv_period).r;
}
#endif

// Length of the ray p + s v (v unit, s >= 0) inside the envelope of ellipsoid i's heap, p
// camera-relative (envelopeChord).
float envelopeChord(int i, vec3 p, vec3 v) {
  vec3 inv = record(i, 18).xyz;
  return unitSphereChord((p - record(i, 17).xyz) * inv, v * inv);
}

// Gardner eq. 8 with the light reaching surface point p of ellipsoid i through its heap
// (heapLightAt, from world/formulas/heap.h), plus the light scattered forward through the surface's translucence tr
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
    if (dot(gradient, gradient) > 0.0) n = bentNormal(n, gradient, u_scatter.w);
    float sun_depth = heapDepth(extinction, envelopeChord(i, p, u_to_sun), dot(n, u_to_sun));
    float sky_depth = heapDepth(extinction, envelopeChord(i, p, vec3(0.0, 0.0, 1.0)), n.z);
    vec3 heap = heapLight(sun_depth, sky_depth, u_scatter.y);
    light = heap.xy;
    direct = heap.z;
  }
  float outside = 1.0 - record(i, 18).w;
  light.x *= outside;
  direct *= outside;
  float n_dot_l = dot(n, u_to_sun);
  float diffuse = skinDiffuse(n_dot_l, u_scatter.z);
  float sun = light.x;
  float highlight = 0.0;
#ifdef SPECULAR
  if (n_dot_l > 0.0) highlight = phongHighlight(n, n_dot_l, u_to_sun, -normalize(r), u_shading.w);
#endif
  float intensity = heapLitIntensity(u_shading, sun, light.y, diffuse, highlight, it);
  vec3 d = normalize(r);
  intensity += u_scatter.x * forwardScattered(direct, dot(d, u_to_sun), u_scatter.y) * tr;
  return applyAir(intensity * u_cloud_colour, d, distance);
}

// Gardner eq. 11 given the threshold excess x = It - T1 - (T2 - T1)(1 - g): opacity 1 - TR.
float opacityFromExcess(float x) { return 1.0 - translucence(x, u_thresholds.z); }

// Premultiplied colour and opacity of ellipsoid i where the ray r meets it at s.
vec4 ellipsoidSurface(int i, vec3 r, float s) {
  vec3 p = s * r;
  vec3 n = normalize(gradientFromUnit(i, record(i, 3).xyz + s * toUnit(i, r)));
  n = facingViewer(n, r);
  // Ray differentials on the tangent plane: the hit moves by s (dr - r (n.dr) / (n.r)).
  vec3 drx = u_right * (2.0 / u_viewport.x), dry = u_up * (2.0 / u_viewport.y);
  float n_dot_r = min(dot(n, r), -1e-4 * length(r));
  vec3 dpdx = s * (drx - r * (dot(n, drx) / n_dot_r));
  vec3 dpdy = s * (dry - r * (dot(n, dry) / n_dot_r));
  float it = solidValue(p, dpdx, dpdy);
  float excess = limbExcess(it, u_thresholds.x, u_thresholds.y, limbG(i, r));
  float opacity = opacityFromExcess(excess);
  float alpha = opacity * record(i, 4).w;
  return vec4(surfaceColour(i, n, r, p, it, 1.0 - opacity, s * length(r)) * alpha, alpha);
}

// Whether a hit at s (units of r) shows in this pass: in front of the ground and targets,
// and in the pass's layer band.
bool hitShows(vec3 r, float s, float limit) { return s > 0.0 && s < limit && inBand(s * r.z); }
