#include "world/formations/genus.h"

#include <array>

namespace nephele {
namespace {

// Heaps: 20 per km of light extinction puts the sky light under a heap's middle at about a
// third of the open sky's (MODEL.md section 14). T0 = 1 keeps the texture's product positive
// nearly everywhere, so with T2 - T1 = 0.8 its variation moves a lobe's edge across the outer
// part of its radius: the outline is ragged down to the finest term the pixel shows (divider
// dimension 1.19 at 640x480; docs/ACCURACY.md, "Outline figures"). The band is as wide as the
// far deck allows: with a wider one, far heaps, their fine terms faded, draw less cover than
// the deck beyond them ("Tried and not kept"). The texture is finer for a cumulonimbus's size,
// its lobes being a smaller part of its width. Ambient a = 0.1: a heap's shaded side is lit by
// the sky (K, section 14), so eq. 8's constant floor is kept low: lit from the side, a heap's
// sunlit half is 1.94 times its shaded half (2.71 for a cumulonimbus; 1.5 asked, 2 aimed at)
// and its base 0.19 of its sunlit top's luminance ("Look figures").
constexpr HeapLook kNoHeaps{1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 6.0, 5};
constexpr HeapLook kCumulusHeaps{1.0, 0.1, 0.3, -0.4, 0.4, 0.08, 0.02, 1.0, 12.0, 6};
constexpr HeapLook kCumulonimbusHeaps{0.9, 0.1, 0.3, -0.3, 0.6, 0.12, 0.02, 1.0, 24.0, 7};

// Species (the atlas): humilis, of slight vertical extent and flattened, three times as wide as
// tall in a layer 500 m thick; mediocris, of moderate extent, 1.8 times as wide at 1,200 m (a
// heap 2.2 km across); congestus, markedly vertical, taller than wide (width 0.6 of the height)
// at 4,000 m, a tower of stacked mounds (MODEL.md section 10). Between the rows a heap's width
// grows as about the 0.4th power of the thickness up to mediocris and barely (0.09th) beyond,
// so a developing layer grows its heaps upward. A cumulonimbus's width is twice the thickness:
// its tower spans about 0.9 of it and its anvil three times the tower.
constexpr Species kCumulusSpecies[] = {
    {"humilis", 500.0, 3.0}, {"mediocris", 1200.0, 1.8}, {"congestus", 4000.0, 0.6}};
constexpr Species kCumulonimbusSpecies[] = {{"capillatus incus", 9000.0, 2.0}};

// Sky planes' amplitude ratios (MODEL.md section 2, "amplitude ratio"): chosen with
// realism_bench so that the drawn field's transect spectrum comes within -5/3 +- 0.3
// (docs/ACCURACY.md, "Realism"): higher than Gardner's 0.707 for the smooth veil and dark deck
// (cirrostratus, nimbostratus), lower for the cellular stratocumulus and altocumulus (the
// altocumulus with a softer transition); the rest keep 0.707.
// Visibility inside a layer (MODEL.md section 5): Koschmieder's 3.9 / beta with the extinction
// of the cloud's droplets or crystals, beta = 3 LWC / (2 rho_w r_e) (liquid water content LWC,
// effective radius r_e): about 0.03 per metre for stratus (LWC 0.2 g/m3, r_e 10 um), 130 m;
// wetter nimbostratus 60 m, stratocumulus 120 m, altocumulus 150 m, altostratus 250 m; ice
// clouds, far thinner (extinction 0.1 to 1 per km): cirrus 5 km, cirrostratus 3 km,
// cirrocumulus 1 km. The heaps' decks have none: among heaps the air is clear, and each heap
// has its own veil (section 15).
// Indexed by CloudType. Typical layers: the atlas's altitude bands for mid-latitudes.
constexpr std::array<Genus, kCloudTypeCount> kGenera{{
    {"none", 700.0, 500.0, {0, 0, 1, 0.707, 0, 0, 0, 0, 0, 0, 0, false, 0}, false, kNoHeaps, {}},
    // cells
    {"altocumulus",
     4000.0,
     700.0,
     {3.0e-3, 3.0e-3, 6, 0.35, 0.5, 90.0, 0.20, 0.95, 0.55, 0.50, 1, false, 150},
     false,
     kNoHeaps,
     {}},
    // a sheet
    {"altostratus",
     4000.0,
     700.0,
     {1.2e-3, 1.2e-3, 5, 0.707, 2.0, 90.0, 0.50, 0.72, 0.70, 0.35, 2, false, 250},
     false,
     kNoHeaps,
     {}},
    // ripples
    {"cirrocumulus",
     8000.0,
     600.0,
     {8.0e-3, 6.5e-3, 6, 0.707, 0.5, 90.0, 0.15, 1.00, 0.70, 0.50, 1, false, 1000},
     false,
     kNoHeaps,
     {}},
    // a veil
    {"cirrostratus",
     8000.0,
     600.0,
     {1.0e-3, 1.0e-3, 4, 0.84, 2.0, 90.0, 3.00, 1.00, 0.80, 0.30, 1, true, 3000},
     false,
     kNoHeaps,
     {}},
    // streaks
    {"cirrus",
     8000.0,
     600.0,
     {1.0e-3, 0.35e-3, 5, 0.707, 0.2, 30.0, 0.50, 1.00, 0.75, 0.60, 1, false, 5000},
     false,
     kNoHeaps,
     {}},
    // towers over a dark deck
    {"cumulonimbus",
     900.0,
     9000.0,
     {1.0e-3, 1.0e-3, 4, 0.707, 2.0, 90.0, 0.80, 0.42, 0.80, 0.30, 1, false, 0},
     true,
     kCumulonimbusHeaps,
     kCumulonimbusSpecies},
    // heaps over a stratocumulus deck
    {"cumulus",
     1200.0,
     1200.0,
     {2.0e-3, 1.6e-3, 6, 0.707, 0.6, 90.0, 0.12, 0.82, 0.55, 0.55, 1, false, 0},
     true,
     kCumulusHeaps,
     kCumulusSpecies},
    // a dark deck three planes deep
    {"nimbostratus",
     900.0,
     2500.0,
     {1.0e-3, 1.0e-3, 4, 0.86, 2.0, 90.0, 0.80, 0.42, 0.80, 0.30, 3, false, 60},
     false,
     kNoHeaps,
     {}},
    // lumps
    {"stratocumulus",
     700.0,
     500.0,
     {2.0e-3, 1.6e-3, 6, 0.55, 0.6, 90.0, 0.12, 0.82, 0.55, 0.55, 1, false, 120},
     false,
     kNoHeaps,
     {}},
    // a grey sheet
    {"stratus",
     700.0,
     500.0,
     {1.5e-3, 1.5e-3, 4, 0.707, 2.5, 90.0, 0.60, 0.66, 0.75, 0.30, 2, false, 130},
     false,
     kNoHeaps,
     {}},
}};

}  // namespace

const Genus& genus(CloudType type) {
  return kGenera[std::size_t(type)];
}

}  // namespace nephele
