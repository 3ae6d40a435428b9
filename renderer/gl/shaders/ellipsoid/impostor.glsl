
layout(binding = 12) uniform sampler2D u_impostor;  // premultiplied colour, coverage
in vec2 v_uv;
in vec3 v_position;  // camera-relative point on the billboard
void main() {
  // The billboard stands for the cloud: hidden where the ground or a target is nearer, and
  // cut by the layer band at its own height.
  if (length(v_position) >= opaqueDistance(v_position) || !inBand(v_position.z)) discard;
  o_colour = texture(u_impostor, v_uv);
}
