#pragma once
// The database on the Earth (MODEL.md section 13): geodetic positions on the WGS 84 ellipsoid,
// Earth-centred coordinates, and the flat database's metres east, north and up of the site.
#include <glm/glm.hpp>

namespace nephele {

// WGS 84 (NIMA TR8350.2): semi-major axis (m) and flattening.
inline constexpr double kWgs84A = 6378137.0;
inline constexpr double kWgs84F = 1.0 / 298.257223563;

struct Geodetic {
  double latitude_deg = 0.0;   // north positive
  double longitude_deg = 0.0;  // east positive
  double height_m = 0.0;       // above the ellipsoid
};

// Earth-centred, Earth-fixed metres: x towards (0 N, 0 E), z towards the north pole.
glm::dvec3 earthCentred(const Geodetic& g);
// The inverse, by Bowring's iteration to a millimetre's hundredth; longitude in (-180, 180].
Geodetic geodeticFromEarthCentred(glm::dvec3 p);

// The flat database about a site on the ellipsoid. A point's east and north are those of its
// foot on the ellipsoid in the site's east-north-up frame (through Earth-centred coordinates,
// in double); its up is its height, so that altitudes keep their meaning in the flat world
// (MODEL.md section 13). Meaningful within a few thousand kilometres of the site, where the
// foot's up-coordinate is still well below the tangent plane's curvature limit.
class LocalFrame {
 public:
  LocalFrame(double latitude_deg, double longitude_deg);
  glm::dvec3 toLocal(const Geodetic& g) const;
  // The geodetic position of a database point: the ellipsoid point whose east and north are
  // (x, y), at height z. Points farther from the site than the Earth's radius have none; they
  // are clamped to the site's horizon.
  Geodetic toGeodetic(glm::dvec3 local) const;

 private:
  glm::dvec3 origin_, east_, north_, up_;
};

}  // namespace nephele
