
// One caster's footprint on the ground (CloudShadows::footprint): the bounding sphere's shadow
// in a square, as one instanced quad.
layout(binding = 13) uniform samplerBuffer u_casters;
uniform vec3 u_to_sun;
uniform float u_half;
flat out int v_caster;
void main() {
  vec4 c = texelFetch(u_casters, gl_InstanceID * 4);
  vec2 centre = planeCrossing(c.xyz, 0.0, u_to_sun);
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1) * 2.0 - 1.0;
  v_caster = gl_InstanceID;
  gl_Position = vec4((centre + corner * (c.w / u_to_sun.z)) / u_half, 0.0, 1.0);
}
