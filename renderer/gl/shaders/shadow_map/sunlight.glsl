
// One caster's share of the sunlight at each ground texel its footprint covers
// (world/formations/cloud_shadow.cpp casterSunlight, with world/formulas/shadow.h); the
// map's blending multiplies the casters' shares.
layout(binding = 13) uniform samplerBuffer u_casters;
layout(binding = 12) uniform sampler2D u_tables;  // kTableSize x tables: C(g)
uniform vec3 u_to_sun;
uniform float u_half;
uniform float u_size;
flat in int v_caster;
layout(location = 0) out vec4 o_light;
void main() {
  vec2 ground = (gl_FragCoord.xy / u_size * 2.0 - 1.0) * u_half;
  int k = v_caster * 4;
  vec4 c = texelFetch(u_casters, k), w0 = texelFetch(u_casters, k + 1);
  vec4 w1 = texelFetch(u_casters, k + 2), w2 = texelFetch(u_casters, k + 3);
  vec3 rel = vec3(ground, 0.0) - c.xyz;
  vec3 o = vec3(dot(w0.xyz, rel), dot(w1.xyz, rel), dot(w2.xyz, rel));
  vec3 w = vec3(dot(w0.xyz, u_to_sun), dot(w1.xyz, u_to_sun), dot(w2.xyz, u_to_sun));
  float chord = unitSphereChord(o, w);
  float light = 1.0;
  if (chord > 0.0) {
    vec2 cell = tableCell(sunRayLimb(o, w), kTableSize - 1);
    int i = int(cell.x), row = int(w2.w);
    float opacity = mix(texelFetch(u_tables, ivec2(i, row), 0).r,
                        texelFetch(u_tables, ivec2(i + 1, row), 0).r, cell.y);
    light = lobeSunlight(opacity, w1.w * chord, kDiffuseAsymmetry);
  }
  o_light = vec4(light);
}
