#pragma once
// Gardner's shading equation (MODEL.md section 3) and translucence (MODEL.md section 4).
#include <glm/glm.hpp>

namespace nephele {

struct ShadingParams {
  double ambient = 0.4;           // a
  double texture_fraction = 0.5;  // t
  double specular = 0.0;          // s
  double shininess = 8.0;         // e
};

// Gardner eq. 8 from its terms: I = (1 - a){(1 - t)[(1 - s) Id + s Is] + t It} + a.
double gardnerIntensity(const ShadingParams& shading, double diffuse, double highlight,
                        double texture_value);

// Gardner eq. 8 lit through a heap (MODEL.md section 14; world/formulas/heap.h): the sun's
// terms times its share `sun`, the ambient term times the sky's share `sky`.
double heapLitIntensity(const ShadingParams& shading, double sun, double sky, double diffuse,
                        double highlight, double texture_value);

// Id = max(0, N.L) and Is = max(0, R.V)^e at a surface (0 where N.L <= 0 or s = 0), N turned
// towards the viewer unless `turn` is false (a lighting normal, such as heapLitNormal's, that
// may face away); n_dot_l is N.L itself, negative on the side turned from the sun.
struct DiffuseHighlight {
  double diffuse = 0.0, highlight = 0.0, n_dot_l = 0.0;
};
DiffuseHighlight diffuseHighlight(const ShadingParams& shading, glm::dvec3 normal,
                                  glm::dvec3 to_sun, glm::dvec3 to_viewer, bool turn = true);

// Gardner eq. 8 at a surface: Id and Is from the geometry. `normal` is any surface normal
// (it is turned towards the viewer here), `to_sun` and `to_viewer` are unit vectors.
double gardnerIntensity(const ShadingParams& shading, double texture_value, glm::dvec3 normal,
                        glm::dvec3 to_sun, glm::dvec3 to_viewer);

// The mean of max(0, N.L) over the visible disc of a Lambertian sphere at phase angle alpha
// (the angle between the directions to the sun and to the viewer): 2/3 (sin alpha +
// (pi - alpha) cos alpha) / pi. A far deck standing for heaps is lit so (MODEL.md section 11).
double sphereDiffuse(double cos_alpha);

// Gardner eq. 9: translucence of a sky plane for texture value It, threshold T1 and
// transition width D. D = 0 is a hard threshold.
double skyPlaneTranslucence(double texture_value, double threshold, double transition);

// Gardner eq. 11: the threshold rises from T1 at the centre (g = 1) to T2 at the limb (g = 0).
double ellipsoidTranslucence(double texture_value, double threshold_centre, double threshold_limb,
                             double limb_g, double transition);

}  // namespace nephele
