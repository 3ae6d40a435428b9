#pragma once
// Shared fixture of the GL image tests: one platform and renderer per suite, presets at test
// size, and an image comparison that writes the actual, expected and 8x difference images to
// NEPHELE_TEST_OUTPUT when it fails.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "config/scene_file.h"
#include "image/image_encoding.h"
#include "image/image_metrics.h"
#include "renderer/gl/gl_renderer.h"
#include "renderer/reference/reference_renderer.h"

namespace nephele {

class GlRenderTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string error;
    platform_ = createGlPlatform(GlBackend::kAuto, error).release();
    ASSERT_NE(platform_, nullptr) << error;
    renderer_ = new GlRenderer(*platform_);
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete platform_;
  }

  static SceneFile preset(const std::string& name, int width = 160, int height = 120) {
    SceneFile file;
    const std::string path = NEPHELE_SOURCE_DIR "/config/scenes/" + name + ".toml";
    EXPECT_EQ(loadSceneFile(path, file), "");
    file.scene.camera.width = width;
    file.scene.camera.height = height;
    return file;
  }

  // Channels not finite or out of range: colour in [0, 64] (HDR suns may exceed 1),
  // coverage in [0, 1].
  static int outOfRange(const FloatImage& image) {
    int bad = 0;
    for (std::size_t i = 0; i < image.rgba.size(); ++i) {
      const float v = image.rgba[i];
      const float hi = i % 4 == 3 ? 1.0f : 64.0f;
      bad += !(std::isfinite(v) && v >= 0.0f && v <= hi);
    }
    return bad;
  }

  static void expectClose(const FloatImage& actual, const FloatImage& expected, double min_psnr,
                          double max_abs, const std::string& name) {
    const ImageError e = compareImages(actual, expected);
    EXPECT_EQ(e.non_finite, 0) << name;
    EXPECT_GE(e.psnr_db, min_psnr) << name;
    EXPECT_LE(e.max_abs, max_abs) << name;
    if (e.non_finite == 0 && e.psnr_db >= min_psnr && e.max_abs <= max_abs) return;
    writeFailureImages(actual, expected, name);
  }

  // Pixels whose coverage differs by more than `tolerance`, at most `max_pixels` of them;
  // writes the images when there are more.
  static void expectCoverageClose(const FloatImage& actual, const FloatImage& expected,
                                  float tolerance, int max_pixels, const std::string& name) {
    int differing = 0;
    for (std::size_t i = 3; i < actual.rgba.size(); i += 4)
      differing += !(std::abs(actual.rgba[i] - expected.rgba[i]) <= tolerance);
    EXPECT_LE(differing, max_pixels) << name << ": coverage differs by over " << tolerance;
    if (differing <= max_pixels) return;
    writeFailureImages(actual, expected, name);
  }

  static void writeFailureImages(const FloatImage& actual, const FloatImage& expected,
                                 const std::string& name) {
    const std::filesystem::path dir(NEPHELE_TEST_OUTPUT);
    std::filesystem::create_directories(dir);
    writeImageFile((dir / (name + "_actual.png")).string(), actual);
    writeImageFile((dir / (name + "_expected.png")).string(), expected);
    writeImageFile((dir / (name + "_diff.png")).string(), differenceImage(actual, expected, 8.0f));
    ADD_FAILURE() << name << ": images written to " << dir;
  }

  static inline GlPlatform* platform_ = nullptr;
  static inline GlRenderer* renderer_ = nullptr;
};

}  // namespace nephele
