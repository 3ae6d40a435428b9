
layout(location = 1) out vec4 o_history;
layout(binding = 12) uniform sampler2D u_samples;
layout(binding = 4) uniform sampler2D u_sample_distance;
layout(binding = 5) uniform sampler2D u_history;
uniform ivec2 u_sample_origin;  // the pixel of sample (0, 0)
uniform vec3 u_prev_x;          // the last frame's clip rows: right / (tan(vfov/2) aspect),
uniform vec3 u_prev_y;          // up / tan(vfov/2)
uniform vec3 u_prev_w;          // and forward
uniform vec3 u_prev_shift;      // a cloud point's position from the last eye, less from this one
const float kResolveMargin = 0.05;
vec4 resolve() {
  ivec2 q = ivec2(gl_FragCoord.xy) - u_sample_origin;
  ivec2 c = q / SHADING_RATE, f = q - c * SHADING_RATE;
  ivec2 top = textureSize(u_samples, 0) - 1;
  ivec2 c1 = min(c + 1, top);
  vec4 s00 = texelFetch(u_samples, c, 0), s10 = texelFetch(u_samples, ivec2(c1.x, c.y), 0);
  vec4 s01 = texelFetch(u_samples, ivec2(c.x, c1.y), 0), s11 = texelFetch(u_samples, c1, 0);
  if (f == ivec2(0)) return s00;
  vec2 w = vec2(f) / float(SHADING_RATE);
  vec4 blend = mix(mix(s00, s10, w.x), mix(s01, s11, w.x), w.y);
  // The four samples' distances in one gather (its texels c and c + 1 on each axis).
  vec4 d = textureGather(u_sample_distance, vec2(c + 1) / vec2(top + 1), 0);
  // The nearest of the samples that hit: an edge reprojects with its foreground.
  vec4 hit = mix(vec4(3.0e38), d, greaterThan(d, vec4(0.0)));
  float distance = min(min(hit.x, hit.y), min(hit.z, hit.w));
  if (distance >= 3.0e38) return blend;
  vec3 point = normalize(viewRay()) * distance + u_prev_shift;
  float depth = dot(point, u_prev_w);
  if (depth <= 0.0) return blend;
  vec2 uv = 0.5 * vec2(dot(point, u_prev_x), dot(point, u_prev_y)) / depth + 0.5;
  if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return blend;
  vec4 last = textureLod(u_history, uv, 0.0);
  // Where the last frame had nothing that this one's samples see, it cannot vouch.
  if (last.a <= 0.0 && blend.a > 0.0) return blend;
  // Kept within the four samples' range widened by that range and kResolveMargin either
  // side: soft detail between the samples survives, a stale surface (a heap since moved or
  // grown, what was hidden coming into view) does not.
  vec4 lo = min(min(s00, s10), min(s01, s11)), hi = max(max(s00, s10), max(s01, s11));
  vec4 margin = hi - lo + kResolveMargin;
  return clamp(last, max(lo - margin, 0.0), hi + margin);
}
void main() {
  o_colour = resolve();
  o_history = o_colour;
}
