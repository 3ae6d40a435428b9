
uniform int u_index;
uniform vec2 u_atlas_size;
layout(binding = 11) uniform sampler2D u_atlas;
void main() {
  vec4 rect = record(u_index, 10), tile = record(u_index, 15);
  vec2 ndc = 2.0 * gl_FragCoord.xy / u_viewport - 1.0;
  vec2 uv = (ndc - rect.xy) / (rect.zw - rect.xy);
  vec2 texel = tile.xy + clamp(uv * tile.zw, vec2(0.5), tile.zw - 0.5);
  vec4 t = texture(u_atlas, texel / u_atlas_size);
  // Elinas' colour-matrix step, here in the shader: alpha = (It - T1 - (T2 - T1)(1 - g)) / D.
  float alpha = opacityFromExcess(t.a) * record(u_index, 4).w;
  vec3 r = viewRay();
  float s = hitEllipsoid(u_index, r);
  // A tile texel just outside the exact silhouette (no hit) stands at the ray's closest
  // approach to the centre, so a cloud drawn in several bands draws it in exactly one.
  if (s <= 0.0) s = max(dot(record(u_index, 14).xyz, r) / dot(r, r), 0.0);
  if (!hitShows(r, s, opaqueDistance(r) / length(r))) discard;
  o_colour = vec4(t.rgb * alpha, alpha);
}
