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

// Where the database lies on the Earth: its origin's latitude and longitude, and its grid
// north, the true bearing of its +Y axis at the origin (degrees clockwise from true north; 0
// until the world first re-centres, MODEL.md section 13).
struct Site {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double grid_deg = 0.0;
  bool operator==(const Site&) const = default;
};

// The flat database about a site on the ellipsoid. A point's X and Y are those of its foot on
// the ellipsoid in the site's east-north-up frame turned by the site's grid north (through
// Earth-centred coordinates, in double); its up is its height, so that altitudes keep their
// meaning in the flat world (MODEL.md section 13). True to 0.1 % in distance within about
// 280 km of the site (the foot's radial scale is cos(d / R)), which re-centring keeps.
class LocalFrame {
 public:
  LocalFrame(double latitude_deg, double longitude_deg)
      : LocalFrame(Site{latitude_deg, longitude_deg}) {}
  explicit LocalFrame(const Site& site);
  glm::dvec3 toLocal(const Geodetic& g) const;
  // The database bearing (degrees clockwise from +Y) of true north at `g`: a true heading h
  // is the database heading h + northBearing(g). At the site it is -grid_deg; elsewhere the
  // meridians converge by about (longitude - site's) sin(latitude).
  double northBearing(const Geodetic& g) const;
  // The geodetic position of a database point: the ellipsoid point whose east and north are
  // (x, y), at height z. Points farther from the site than the Earth's radius have none; they
  // are clamped to the site's horizon.
  Geodetic toGeodetic(glm::dvec3 local) const;

 private:
  glm::dvec3 origin_, x_, y_, up_;  // the database's axes, Earth-centred
};

// The world re-centred on a new origin (MODEL.md section 13): the site at `latitude_deg`,
// `longitude_deg` whose grid north makes the map from `from`'s database to its own a pure
// translation at the new origin (no turn there), and that translation: a point at database
// X, Y of `from` is at X, Y - shift of `to`, to second order in its distance from the new
// origin (0.4 m at 10 km, 9 m at 100 km for a 50 km move).
struct Recentring {
  Site to;
  glm::dvec2 shift{0.0};  // the new origin in `from`'s database, metres
};
Recentring recentred(const Site& from, double latitude_deg, double longitude_deg);

}  // namespace nephele
