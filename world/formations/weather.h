#pragma once
// Weather layers onto formations (MODEL.md section 10): one mapping from a layer's cloud type,
// base, thickness and coverage to what the world draws, shared by set_weather, the Modbus
// weather registers and scene files. Stratiform genera are Gardner sky planes (one, or a
// stack of them through the layer's thickness), convective genera fields of heaps over an
// optional deck.
#include <cstdint>
#include <string>
#include <vector>

#include "world/formations/cloud_field.h"
#include "world/scene.h"

namespace nephele {

// What one weather layer adds to the world. Names start with `prefix`.
struct WeatherClouds {
  std::vector<CloudLayer> layers;
  std::vector<CloudField> fields;
};
WeatherClouds weatherClouds(const WeatherLayer& weather, const std::string& prefix,
                            std::uint64_t seed);
// The seed of weather layer `layer` (1-based) of a scene seeded `scene_seed`: the same layer
// from set_weather, Modbus or a scene file draws the same sky.
std::uint64_t weatherSeed(std::uint64_t scene_seed, int layer);

// A layer of `type` at a base and thickness typical of its genus (the WMO cloud atlas's
// altitude bands for mid-latitudes), with the given coverage.
WeatherLayer typicalWeatherLayer(CloudType type, double coverage);

// Gardner's T1 for a layer texture such that, seen straight down through `planes` identical
// planes with transition D, a fraction `coverage` of the ground has opacity >= 1/2 (SPEC
// section 9). Estimated from the texture's values at 16384 seeded points spread over many
// texture periods.
double thresholdForCoverage(const LayerTextureSpec& texture, double transition, int planes,
                            double coverage);
// Fills far.threshold with thresholdForCoverage of one plane at c = 0, 1/16, ..., 1.
void calibrateFarCover(const LayerTextureSpec& texture, double transition, FarCover& far);

}  // namespace nephele
