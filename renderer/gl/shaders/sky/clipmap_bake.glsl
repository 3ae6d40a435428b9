
uniform ivec2 u_bake_first;   // the window's first lattice index, modulo N
uniform int u_bake_size;      // N
uniform vec2 u_bake_texel;    // metres per texel of this ring
uniform float u_bake_terms;   // n - l
void main() {
  ivec2 rel = (ivec2(gl_FragCoord.xy) - u_bake_first + u_bake_size) % u_bake_size;
  o_colour = vec4(truncatedValue(0, (vec2(rel) + 0.5) * u_bake_texel, u_bake_terms));
}
