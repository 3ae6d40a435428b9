// The render knobs' table (renderer/render_knobs.inc): its values, its one check, and the
// documents generated from it.
#include "renderer/render_knobs.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <set>
#include <string>

#include "renderer/render_settings.h"

namespace nephele {
namespace {

using ::testing::HasSubstr;

std::string readSourceFile(const std::string& path) {
  std::ifstream in(std::string(NEPHELE_SOURCE_DIR) + "/" + path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(RenderKnobs, NamesAndFlagsAreUnique) {
  std::set<std::string_view> names;
  for (const RenderKnob& knob : renderKnobs()) {
    EXPECT_TRUE(names.insert(knob.name).second) << knob.name;
    EXPECT_EQ(knob.flag().substr(0, 2), "--");
    EXPECT_EQ(knob.flag().find('_'), std::string::npos) << knob.flag();
  }
  ASSERT_NE(findRenderKnob("heap_shading_rate"), nullptr);
  EXPECT_EQ(findRenderKnob("heap_shading_rate")->flag(), "--heap-shading-rate");
  EXPECT_EQ(findRenderKnob("no_such_knob"), nullptr);
}

// The row's default is the field's, every default and swept value passes the one check, and
// a value set is the value read back.
TEST(RenderKnobs, DefaultsAndSweepsAreAllowed) {
  const RenderSettings defaults;
  EXPECT_EQ(validateRenderSettings(defaults), "");
  EXPECT_EQ(findRenderKnob("heap_range")->default_value, HeapDrawing{}.range_m);
  for (const RenderKnob& knob : renderKnobs()) {
    EXPECT_EQ(knob.get(defaults), knob.default_value) << knob.name;
    EXPECT_EQ(knobError(knob, knob.default_value), "") << knob.name;
    for (double value : knob.sweep) {
      EXPECT_EQ(knobError(knob, value), "") << knob.name << " " << value;
      RenderSettings s;
      knob.set(s, value);
      EXPECT_EQ(knob.get(s), value) << knob.name;
      double parsed = -1.0;
      EXPECT_EQ(parseKnobText(knob, knob.format(value), parsed), "") << knob.name;
      EXPECT_EQ(parsed, value) << knob.name;
    }
  }
}

TEST(RenderKnobs, ErrorsNameTheKnobAndWhatIsAllowed) {
  auto error = [](const char* name, double value) {
    return knobError(*findRenderKnob(name), value);
  };
  EXPECT_EQ(error("tile_resolution", 12),
            "tile_resolution: 12 is not allowed (allowed: 0 for adaptive, or a power of two "
            "from 8 to 1024)");
  EXPECT_EQ(error("tile_resolution", 0), "");
  EXPECT_EQ(error("tile_resolution", 2048),
            "tile_resolution: 2048 is out of range (allowed: 0 for adaptive, or a power of two "
            "from 8 to 1024)");
  EXPECT_EQ(error("heap_shading_rate", 3),
            "heap_shading_rate: 3 is not allowed (allowed: 1, 2 or 4 pixels between samples)");
  EXPECT_EQ(error("shadow_map_size", 100),
            "shadow_map_size: 100 is out of range (allowed: 0 for no cloud shadows, or 256 to "
            "4096 texels a side)");
  EXPECT_THAT(error("impostor_tolerance", std::nan("")), HasSubstr("is out of range"));
  EXPECT_THAT(error("sea_waves", 16.5), HasSubstr("sea_waves: 16.5 is out of range"));
  EXPECT_EQ(error("ellipsoid_order", 2),
            "ellipsoid_order: 2 is out of range (allowed: centre or per-pixel)");
  double value = 0.0;
  EXPECT_EQ(parseKnobText(*findRenderKnob("limb"), "round", value),
            "limb: 'round' is not allowed (allowed: exact or spotlight)");
  EXPECT_THAT(parseKnobText(*findRenderKnob("tessellation"), "2.5", value),
              HasSubstr("tessellation: '2.5' is not an integer (allowed: 0 for adaptive"));
  EXPECT_EQ(parseKnobText(*findRenderKnob("volume_step"), "0.5", value), "");
  EXPECT_EQ(value, 0.5);
}

// README.md's [render] block and docs/ACCURACY.md's knob table are the table's; regenerate
// them with `nephele knobs` and `nephele knobs --markdown`.
TEST(RenderKnobs, ReadmeHoldsTheGeneratedRenderBlock) {
  const std::string readme = readSourceFile("README.md");
  const std::string expected = knobsToml();
  EXPECT_NE(readme.find(expected), std::string::npos)
      << "README.md's [render] block should hold `nephele knobs`:\n"
      << expected;
}

TEST(RenderKnobs, AccuracyHoldsTheGeneratedKnobTable) {
  const std::string accuracy = readSourceFile("docs/ACCURACY.md");
  const std::string expected = knobsMarkdown(measuredKnobColumns(accuracy));
  EXPECT_NE(accuracy.find(expected), std::string::npos)
      << "docs/ACCURACY.md's knob table should be `nephele knobs --markdown` (the last two "
         "columns are measured, by hand):\n"
      << expected;
}

}  // namespace
}  // namespace nephele
