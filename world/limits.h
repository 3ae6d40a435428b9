#pragma once
// Allowed ranges for user input, shared by scene files, the command line, the socket
// protocol and the Modbus register map.

namespace nephele {

struct Limits {
  static constexpr int kMaxImageSide = 16384;      // GL_MAX_RENDERBUFFER_SIZE on llvmpipe
  static constexpr double kMaxCoordinate = 1.0e8;  // metres from the origin
  static constexpr double kMaxAltitude = 1.0e5;
  static constexpr double kMinVfov = 0.01, kMaxVfov = 179.0;
  // Angles in degrees, each allowed from -max to +max; sun azimuth and elevation follow
  // heading and pitch.
  static constexpr double kMaxHeading = 360.0, kMaxPitch = 90.0, kMaxRoll = 180.0;
  static constexpr double kMaxTime = 1.0e9;  // seconds of simulation time
  // Ellipsoid semi-axes and target sizes, metres: zero, negative and NaN are rejected.
  static constexpr double kMinRadius = 1.0e-3, kMaxRadius = 1.0e5;
  static constexpr int kMaxEllipsoidsPerCloud = 4096;
  // Automaton steps are simulated one by one: a scene with automaton clouds may start at most
  // a day into its simulation.
  static constexpr double kMaxAutomatonTime = 86400.0;
  static constexpr int kMaxAutomata = 256;
};

}  // namespace nephele
