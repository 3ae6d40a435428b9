
layout(binding = 12) uniform sampler2D u_samples;  // bilinear: the blend in one fetch
void main() {
  vec2 at = floor(gl_FragCoord.xy) / float(SHADING_RATE) + 0.5;  // sample c's centre is c + 0.5
  o_colour = textureLod(u_samples, at / vec2(textureSize(u_samples, 0)), 0.0);
  if (o_colour.a <= 0.0) discard;
}
