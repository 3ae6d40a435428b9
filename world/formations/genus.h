#pragma once
// The cloud genera in one table (MODEL.md section 10; WMO International Cloud Atlas): for each
// genus its name, the layer a host gets when it names only the genus, and how it is drawn:
// Gardner sky planes with their look, and for the convective genera a field of heaps with
// theirs (the planes are then the deck under the heaps). Weather layers (weather.cpp), the heap
// fields (cloud_field.cpp) and every reader of a genus name (scene files, set_weather, Modbus,
// CIGI through cloudTypeName / cloudTypeFromName) read it. Adding a genus adds a row here, an
// enumerator to CloudType (CIGI's numbering) and its cases to the tests.
#include <string_view>

#include "world/formations/cloud_field.h"

namespace nephele {

// Sky planes (section 10): Gardner texture base frequencies (radians per metre), term count,
// contrast offset T0, lattice-breaking rotation; the transition D, grey level, ambient and
// texture fractions of eq. 8; how many planes stand through the layer's thickness; a veil
// stays translucent at full cover (opacity just above 1/2 where it is thinnest) where a deck
// turns opaque.
struct PlaneLook {
  double fx1, fy1;
  int terms;
  double t0, rotation_deg, transition, grey, ambient, texture_fraction;
  int planes;
  bool veil;
};

// Heaps (sections 10 and 14): colour; ambient and texture fractions of eq. 8; T1, T2 and D of
// eq. 11 (T1 well below zero makes the middle of every ellipsoid opaque whatever the texture,
// T2 above one the limb clear, D how soft the edge is); the light's extinction through a heap
// per metre; a heap's horizontal radius per metre of the layer's thickness.
struct HeapLook {
  double colour, ambient, texture_fraction, t1, t2, d, light_extinction, radius;
};

struct Genus {
  std::string_view name;
  double typical_base_m, typical_thickness_m;  // typicalWeatherLayer
  PlaneLook planes;
  bool heaps;  // a field of heaps (heap_look) over a deck of `planes`
  HeapLook heap_look;
};

// The row of `type` (CloudType::kNone has a row too, drawing nothing); `type` must be one of
// CloudType's values (weatherLayerError refuses others).
const Genus& genus(CloudType type);

}  // namespace nephele
