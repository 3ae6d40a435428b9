#version 450 core
layout(binding = 13) uniform samplerBuffer u_casters;
uniform vec3 u_to_sun;
uniform float u_half;
flat out int v_caster;
void main() {
  vec4 c = texelFetch(u_casters, gl_InstanceID * 4);
  // The footprint (CloudShadows::footprint): the bounding sphere's shadow in a square.
  vec2 centre = c.xy - c.z / u_to_sun.z * u_to_sun.xy;
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1) * 2.0 - 1.0;
  v_caster = gl_InstanceID;
  gl_Position = vec4((centre + corner * (c.w / u_to_sun.z)) / u_half, 0.0, 1.0);
}
