
layout(binding = 13) uniform sampler3D u_volume;  // rho and sunlight of both keyframes
layout(binding = 8) uniform sampler3D u_sky;      // skylight and sun_diffuse of both keyframes
uniform vec3 u_box_min;         // camera-relative box where the density can be non-zero
uniform vec3 u_box_max;
uniform vec3 u_lattice_origin;  // camera-relative position of lattice sample (0, 0, 0)
uniform float u_inv_spacing;    // lattice samples per metre
uniform vec3 u_inv_dims;
uniform float u_blend;          // 0: first keyframe, 1: second
uniform float u_step;           // march step, metres
uniform float u_extinction;     // Ex per metre for density 1
uniform vec3 u_light;           // cloud colour times sun colour
uniform float u_ambient;
uniform vec3 u_to_sun;
uniform float u_phase_g;

// Density, sunlight, skylight and the sunlight's diffuse share (MODEL.md section 6) at
// camera-relative p.
vec4 densityAndLight(vec3 p) {
  vec3 t = ((p - u_lattice_origin) * u_inv_spacing + 0.5) * u_inv_dims;
  vec4 v = texture(u_volume, t);
  vec4 sky = texture(u_sky, t);
  return vec4(mix(v.xy, v.zw, u_blend), mix(sky.xz, sky.yw, u_blend));
}

// The phase function the cloud asks for (world/formulas/volume.h).
float phase(float c) {
#ifdef CORNETTE_SHANKS
  return cornetteShanksPhase(c, u_phase_g);
#else
  return rayleighPhase(c);
#endif
}

// Light scattered towards the viewer per unit of the sun's at sample s (densityAndLight).
float scatteredAt(float phase, vec4 s) {
  return scatteredLight(phase, s.y, s.w, u_ambient, s.z);
}

void main() {
  vec3 d = normalize(viewRay());
  // Slab test against the box; the camera sits at the origin of these coordinates.
  vec3 inv = 1.0 / mix(d, vec3(1e-20), equal(d, vec3(0.0)));
  vec3 s0 = u_box_min * inv, s1 = u_box_max * inv;
  vec3 near = min(s0, s1), far = max(s0, s1);
  float enter = max(max(near.x, near.y), max(near.z, 0.0));
  float leave = min(min(far.x, far.y), far.z);
  leave = min(leave, opaqueDistance(d));  // the ground and targets hide what lies beyond
  // The volume is composited as one surface at its entry (as the reference does), so it
  // belongs to the layer band of its entry point.
  if (!(leave > enter) || !inBand(enter * d.z)) discard;
  int steps = min(int(ceil((leave - enter) / u_step)), MAX_STEPS);
  float ds = (leave - enter) / float(steps);
  float scattering = phase(dot(u_to_sun, d));
  vec3 radiance = vec3(0.0);
  float transmittance = 1.0;
  vec4 a = densityAndLight(enter * d);
  for (int i = 1; i <= steps && transmittance > 1e-3; ++i) {
    vec4 b = densityAndLight((enter + float(i) * ds) * d);
    // Exact attenuation over the step for density linear along it (MODEL.md section 6), with the source
    // held at the mean of the step's ends, as the reference does.
    float segment = segmentTransmittance(a.x, b.x, ds, u_extinction);
    radiance += stepScattered(transmittance, segment, scatteredAt(scattering, a),
                              scatteredAt(scattering, b)) * u_light;
    transmittance *= segment;
    a = b;
  }
  float alpha = 1.0 - transmittance;
  if (alpha <= 0.0) discard;
  // The air (fog, haze) as for a surface at the entry point, on the straight colour.
  o_colour = vec4(alpha * applyAir(radiance / alpha, d, enter), alpha);
}
