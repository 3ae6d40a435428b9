
// One ellipsoid seen from the eye, everything camera-relative (see EllipsoidRenderer); the
// texels of record(i, k) in this order:
struct EllipsoidRecord {
  vec4 w[3];       // rows of W = S^-1 R^T: unit-sphere offset of a camera-relative point
  vec4 eye_unit;   // o = W (eye - centre); w: c = |o|^2 - 1 (> 0: the eye is outside)
  vec4 limb_axis;  // cone axis a; w: surface fade of the in-cloud model
  vec4 p[3];       // rows of P: g = 1 - q.P q with q = d / (d.a) - a
  vec4 l[2];       // rows of L, P = L^T L: spotlight texture coordinates
  vec4 rect;       // screen rectangle in NDC: x0, y0, x1, y1
  vec4 body[3];    // columns of R S: unit sphere to camera-relative offsets
  vec4 centre;     // centre - eye
  vec4 tile;       // atlas tile: texel origin xy, size zw
  vec4 order;      // z: the nearest a hit on it can be, metres (front-to-back order)
  vec4 envelope;   // its heap's envelope (MODEL.md section 14): centre - eye; w extinction
  vec4 inv_radii;  // 1 / the envelope's semi-axes; w: the share of the sunlight the other
                   // clouds above take (MODEL.md section 16), at its centre
};
// Records live in a buffer texture, kRecordTexels RGBA32F texels each: llvmpipe fetches texels
// for eight pixels at once, where a storage buffer is read one pixel at a time.
layout(binding = 13) uniform samplerBuffer u_records;
const int kRecordTexels = 19;
vec4 record(int i, int k) { return texelFetch(u_records, i * kRecordTexels + k); }
