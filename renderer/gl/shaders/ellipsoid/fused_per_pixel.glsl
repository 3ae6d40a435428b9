
// The batch's screen bins, kPerPixelBinSize pixels a side, from bin u_bin_origin on, u_bins_x
// to a row: bin b lists its ellipsoids u_items[u_bins[b].x .. + u_bins[b].y) nearest first
// by the distance no hit on them can be nearer than (the record's order.z, metres).
layout(binding = 7) uniform isamplerBuffer u_bins;   // RG32I: first item, count
layout(binding = 8) uniform isamplerBuffer u_items;  // R32I
uniform ivec2 u_bin_origin;
uniform int u_bins_x;
uniform int u_bin_size;
uniform float u_opaque;  // the coverage past which the walk ends
#ifdef HISTORY
layout(location = 1) out vec4 o_history;  // a continuous view's first frame, kept
#endif
#ifdef SAMPLE_DISTANCE
uniform int u_bins_y;
// The distance in metres at which the walk's coverage passes 1/2 (of the last hit if it never
// does; 0 where nothing is hit): what a continuous view reprojects the sample by.
layout(location = 1) out float o_distance;
#endif

// Hits are ordered by (depth, ellipsoid index), so equal depths still have one order.
bool before(float s, int i, float t, int j) { return s < t || (s == t && i < j); }

// Ellipsoid i's hit on this pixel's ray where it shows, else -1.
float shownHit(int i, vec3 r, float limit) {
  float s = hitEllipsoid(i, r);
  return hitShows(r, s, limit) ? s : -1.0;
}

void main() {
  vec3 r = viewRay();
  float metres_per_unit = length(r);
  float limit = opaqueDistance(r) / metres_per_unit;
  ivec2 bin = ivec2(floor(FRAG_XY / float(u_bin_size))) - u_bin_origin;
#ifdef SAMPLE_DISTANCE
  // Samples shifted by a continuous view's offset reach one sample past the batch's bins on
  // either side, where nothing of the batch is.
  o_distance = 0.0;
  if (any(lessThan(bin, ivec2(0))) || bin.x >= u_bins_x || bin.y >= u_bins_y) discard;
  float depth = 0.0;
#endif
  ivec2 list = texelFetch(u_bins, bin.y * u_bins_x + bin.x).xy;
  // Front to back (MODEL.md section 15): the ellipsoids come nearest bound first, and a hit
  // that no ellipsoid still to come can be in front of is final. Up to four hits wait,
  // nearest first (depth d, ellipsoid id; empty slots at kNone). Each round tests ellipsoids
  // until the nearest waiting hit is final (or four wait: then the nearest goes first), then
  // composites the final hits; the walk ends once the pixel is opaque, since what lies
  // behind would add less than 1/1024. Shading stays out of the testing loop: llvmpipe runs
  // both sides of every branch, so a loop pays for all of its body on every turn.
  const float kNone = 3.0e38;
  const float kOpaque = u_opaque;
  vec4 d = vec4(kNone);
  ivec4 id = ivec4(-1);
  int waiting = 0, k = 0;
  float next = kNone;  // the bound of ellipsoid k, the next to test (kNone when none is left)
  vec4 result = vec4(0.0);
  while (result.a < kOpaque) {
    for (; k < list.y; ++k) {
      int i = texelFetch(u_items, list.x + k).x;
      next = record(i, 16).z / metres_per_unit;
      if (next >= limit) {
        k = list.y;
        break;
      }
      if (waiting == 4 || (waiting > 0 && d.x <= next)) break;
      float s = shownHit(i, r, limit);
      if (s < 0.0) continue;
      // Insert (s, i) in order with constant indices (llvmpipe spills indexed arrays).
      int at = int(before(d.x, id.x, s, i)) + int(before(d.y, id.y, s, i)) +
               int(before(d.z, id.z, s, i));
      d = vec4(at > 0 ? d.x : s, at > 1 ? d.y : (at == 1 ? s : d.x),
               at > 2 ? d.z : (at == 2 ? s : d.y), at == 3 ? s : d.z);
      id = ivec4(at > 0 ? id.x : i, at > 1 ? id.y : (at == 1 ? i : id.x),
                 at > 2 ? id.z : (at == 2 ? i : id.y), at == 3 ? i : id.z);
      ++waiting;
    }
    if (k >= list.y) next = kNone;
    if (waiting == 0) break;
    do {
#ifdef SAMPLE_DISTANCE
      if (result.a < 0.5) depth = d.x;
#endif
      result += (1.0 - result.a) * ellipsoidSurface(id.x, r, d.x);
      d = vec4(d.yzw, kNone);
      id = ivec4(id.yzw, -1);
      --waiting;
    } while (waiting > 0 && d.x <= next && result.a < kOpaque);
  }
  if (result.a <= 0.0) discard;
  o_colour = result;
#ifdef HISTORY
  o_history = result;
#endif
#ifdef SAMPLE_DISTANCE
  o_distance = depth * metres_per_unit;
#endif
}
