#pragma once
// The cloud genera in one table (MODEL.md section 10; WMO International Cloud Atlas): for each
// genus its name, the layer a host gets when it names only the genus, and how it is drawn:
// Gardner sky planes with their look, and for the convective genera a field of heaps with
// theirs (the planes are then the deck under the heaps). Weather layers (weather.cpp), the heap
// fields (cloud_field.cpp) and every reader of a genus name (scene files, set_weather, Modbus,
// CIGI through cloudTypeName / cloudTypeFromName) read it. Adding a genus adds a row here, an
// enumerator to CloudType, its host code if the protocols number it (protocol/cloud_codes.cpp)
// and its cases to the tests; adding a species of a convective genus adds a row to its species
// list and its case to the tests.
#include <span>
#include <string_view>

#include "world/formations/cloud_field.h"

namespace nephele {

// Sky planes (section 10): Gardner texture base frequencies (radians per metre), term count,
// the amplitude ratio between successive terms (section 2), contrast offset T0, lattice-breaking
// rotation; the transition D, grey level, ambient and texture fractions of eq. 8; how many planes
// stand through the layer's thickness; a veil stays translucent at full cover (opacity just above
// 1/2 where it is thinnest) where a deck turns opaque.
struct PlaneLook {
  double fx1, fy1;
  int terms;
  double amplitude_ratio, t0, rotation_deg, transition, grey, ambient, texture_fraction;
  int planes;
  bool veil;
  double in_layer_visibility_m;  // inside the layer (MODEL.md section 5); 0 for heaps' decks
};

// Heaps (sections 10 and 14): colour; ambient and texture fractions of eq. 8; T1, T2 and D of
// eq. 11 (T1 below zero makes the middle of every ellipsoid opaque whatever the texture, T2 how
// far in towards the limb the texture decides the edge, D how soft the edge is); the light's
// extinction through a heap per metre; the solid texture's offset T0, its base frequency in
// radians per metre times the heap's base radius, and its terms (section 2): the texture, not
// the ellipsoids, carries the heap's ragged outline and cauliflower detail ([G]).
struct HeapLook {
  double colour, ambient, texture_fraction, t1, t2, d, light_extinction;
  double texture_offset, texture_cycles;
  int texture_terms;
};

// A species of heap (WMO International Cloud Atlas): the layer thickness it stands for and the
// width of its heaps (twice their base radius) over their height there. A field's heaps take
// the width ratio interpolated between its genus's species in log thickness (power laws between
// the rows, constant beyond the ends), so they change shape smoothly as a layer develops; the
// field's species is the row nearest in log thickness (heapSpecies, cloud_field.h).
struct Species {
  std::string_view name;
  double thickness_m, width_over_height;
};

struct Genus {
  std::string_view name;
  double typical_base_m, typical_thickness_m;  // typicalWeatherLayer
  PlaneLook planes;
  bool heaps;  // a field of heaps (heap_look, species) over a deck of `planes`
  HeapLook heap_look;
  std::span<const Species> species;  // thinnest first; empty without heaps
};

// The row of `type` (CloudType::kNone has a row too, drawing nothing); `type` must be one of
// CloudType's values (weatherLayerError refuses others).
const Genus& genus(CloudType type);

}  // namespace nephele
