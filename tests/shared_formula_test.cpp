// The formulas the GL renderer and the CPU reference share (world/formulas/): each evaluated
// on the same inputs in C++, in double, and in GLSL on the GPU, in float, one fragment per
// case of a float target read back. The inputs are rounded to float first, so the two sides
// differ only by float's arithmetic: each case allows a relative error of kRelative of its
// scale (the magnitude of the terms it sums, where they may cancel), which float's 24 bits
// and llvmpipe's exp and pow meet with room to spare (its acos needs more: sphereDiffuse).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <type_traits>
#include <vector>

#include "gl_test_fixture.h"
#include "renderer/gl/gl_objects.h"
#include "renderer/gl/sky_shaders.h"
#include "world/formulas/air.h"
#include "world/formulas/ellipsoid.h"
#include "world/formulas/far_deck.h"
#include "world/formulas/heap.h"
#include "world/formulas/region.h"
#include "world/formulas/sea.h"
#include "world/formulas/shading.h"
#include "world/formulas/shadow.h"
#include "world/formulas/table.h"
#include "world/formulas/texture.h"
#include "world/formulas/volume.h"

namespace nephele {
namespace {

namespace f = formulas;
constexpr double kRelative = 2e-5;
constexpr std::size_t kChunk = 64;

// An input as the GPU takes it: rounded to float (an integer as it is).
int toFloat(int x) {
  return x;
}
double toFloat(double x) {
  return double(float(x));
}
glm::dvec2 toFloat(glm::dvec2 v) {
  return glm::dvec2(glm::vec2(v));
}
glm::dvec3 toFloat(glm::dvec3 v) {
  return glm::dvec3(glm::vec3(v));
}
glm::dvec4 toFloat(glm::dvec4 v) {
  return glm::dvec4(glm::vec4(v));
}

// The same input as a GLSL expression: its float written out in full and multiplied by a
// uniform 1, so that the compiler cannot fold the formula at compile time, where Mesa would
// evaluate it in C rather than as the GPU does.
std::string glslNumber(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9e", double(float(x)));
  return text;
}
std::string glslArg(double x) {
  return "(" + glslNumber(x) + " * u_one)";
}
std::string glslArg(int x) {
  return "(" + std::to_string(x) + " * int(u_one))";
}
template <int N>
std::string glslArg(glm::vec<N, double> v) {
  std::string s = "(vec" + std::to_string(N) + "(";
  for (int i = 0; i < N; ++i) s += (i ? ", " : "") + glslNumber(v[i]);
  return s + ") * u_one)";
}

struct Case {
  std::string call;  // the GLSL expression
  double cpu = 0.0;  // its value in C++
  double scale = 0.0;
};

class Cases {
 public:
  // `formula` on `args` (rounded to float) in C++, and the GLSL call of `name` on them; the
  // case's scale is max(|value|, floor). A vector result gives a case for each component.
  template <typename Result, typename... Args>
  void add(const std::string& name, Result (*formula)(Args...), double floor,
           std::type_identity_t<Args>... args) {
    const Result cpu = formula(toFloat(args)...);
    std::string call = name + "(";
    bool first = true;
    ((call += (first ? "" : ", ") + glslArg(args), first = false), ...);
    call += ")";
    if constexpr (std::is_same_v<Result, double>) {
      list_.push_back({call, cpu, std::max(std::abs(cpu), floor)});
    } else {
      for (int i = 0; i < Result::length(); ++i)
        list_.push_back({call + "." + "xyzw"[i], cpu[i], std::max(std::abs(cpu[i]), floor)});
    }
  }
  const std::vector<Case>& all() const { return list_; }

 private:
  std::vector<Case> list_;
};

// A fragment stage whose fragment x = i writes case i's value to red.
std::string fragmentSource(const std::vector<Case>& cases) {
  std::string s = "#version 450 core\n";
  s += formulaSource();  // as every stage of the GL renderer holds them
  s += "uniform float u_one;\nlayout(location = 0) out vec4 o_value;\nvoid main() {\n";
  s += "  float v = 0.0;\n  switch (int(gl_FragCoord.x)) {\n";
  for (std::size_t i = 0; i < cases.size(); ++i)
    s += "    case " + std::to_string(i) + ": v = " + cases[i].call + "; break;\n";
  return s + "  }\n  o_value = vec4(v, 0.0, 0.0, 1.0);\n}\n";
}

constexpr char kVertexSource[] = R"(#version 450 core
void main() {
  gl_Position = vec4(float((gl_VertexID & 1) * 4 - 1), float((gl_VertexID >> 1) * 4 - 1), 0.0, 1.0);
}
)";

class SharedFormulaTest : public GlRenderTest {
 protected:
  // Each case's value on the GPU, kChunk cases a draw (one switch over a few hundred cases left
  // those past about the 80th at 0 on llvmpipe).
  static std::vector<float> evaluate(const std::vector<Case>& cases) {
    std::vector<float> values;
    for (std::size_t first = 0; first < cases.size(); first += kChunk) {
      const std::vector<Case> chunk(cases.begin() + first,
                                    cases.begin() + std::min(cases.size(), first + kChunk));
      const std::vector<float> part = evaluateChunk(chunk);
      if (part.size() != chunk.size()) return {};
      values.insert(values.end(), part.begin(), part.end());
    }
    return values;
  }

  static std::vector<float> evaluateChunk(const std::vector<Case>& cases) {
    const GlApi& gl = platform_->gl();
    std::string error;
    GlObject program = createProgram(gl, kVertexSource, fragmentSource(cases), error);
    EXPECT_TRUE(program) << error;
    if (!program) return {};
    const int width = int(cases.size());
    GlObject target = createRenderbuffer(gl), framebuffer = createFramebuffer(gl);
    gl.NamedRenderbufferStorage(target.get(), GL_RGBA32F, width, 1);
    gl.NamedFramebufferRenderbuffer(framebuffer.get(), GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                    target.get());
    EXPECT_TRUE(framebufferUsable(gl, framebuffer.get()));
    GlObject vertex_array = createVertexArray(gl);
    gl.BindFramebuffer(GL_FRAMEBUFFER, framebuffer.get());
    gl.BindVertexArray(vertex_array.get());
    gl.UseProgram(program.get());
    gl.ProgramUniform1f(program.get(), gl.GetUniformLocation(program.get(), "u_one"), 1.0f);
    gl.Disable(GL_BLEND);
    gl.Disable(GL_DEPTH_TEST);
    gl.Disable(GL_SCISSOR_TEST);
    gl.Viewport(0, 0, width, 1);
    gl.DrawArrays(GL_TRIANGLES, 0, 3);
    std::vector<float> rgba(4 * cases.size());
    gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
    gl.ReadPixels(0, 0, width, 1, GL_RGBA, GL_FLOAT, rgba.data());
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
    std::vector<float> values(cases.size());
    for (std::size_t i = 0; i < cases.size(); ++i) values[i] = rgba[4 * i];
    return values;
  }

  // Both sides agree on every case, within kRelative of its scale; each that does not is
  // listed with its call and both values.
  static void expectAgree(const Cases& cases) {
    const std::vector<float> gpu = evaluate(cases.all());
    ASSERT_EQ(gpu.size(), cases.all().size());
    int differing = 0;
    for (std::size_t i = 0; i < gpu.size(); ++i) {
      const Case& c = cases.all()[i];
      const double tolerance = kRelative * c.scale;
      if (std::abs(double(gpu[i]) - c.cpu) <= tolerance) continue;
      ++differing;
      ADD_FAILURE() << "case " << i << ", " << c.call << ": GLSL " << gpu[i] << ", C++ " << c.cpu
                    << ", differ by " << std::abs(double(gpu[i]) - c.cpu) << " > " << tolerance;
    }
    EXPECT_EQ(differing, 0) << "of " << gpu.size() << " cases";
  }
};

constexpr double kFar = 1e30;  // the shaders' endless distance (sky/common.glsl)

TEST_F(SharedFormulaTest, SlabsAgree) {
  Cases cases;
  const glm::dvec3 slabs[] = {{0.0, 100.0, 0.0}, {800.0, 1400.0, 150.0}, {-50.0, 3.0, 40.0}};
  const double heights[] = {-200.0, 0.0, 50.0, 99.9, 100.0, 760.0, 1420.0, 1e4, 1e9};
  for (const glm::dvec3& slab : slabs) {
    const double thickness = slab.y - slab.x + slab.z;
    for (double z : heights) {
      cases.add("slabDensity", &f::slabDensity, 1.0, slab, z);
      cases.add("slabColumn", &f::slabColumn, thickness, slab, z);
    }
    // Level, nearly level, rising and falling rays, near and endless.
    for (double z0 : {2.0, 900.0, 2000.0})
      for (double dz : {0.0, 1e-9, 5e-7, 0.02, -0.02, 0.3, -0.7, 1.0})
        for (double distance : {10.0, 5000.0, kFar}) {
          // The columns' difference loses float's digits of the heights it subtracts.
          const double floor =
              std::abs(distance * dz) < 1e-3 ? distance : (std::abs(z0) + thickness) / std::abs(dz);
          cases.add("slabPath", &f::slabPath, floor, slab, z0, dz, distance);
        }
  }
  // The clear sky from below the horizon to the zenith.
  for (double up : {-0.4, 0.0, 1e-6, 0.2, 1.0})
    cases.add("skyGradient", &f::skyGradient, 1.0, glm::dvec3(0.7, 0.75, 0.8),
              glm::dvec3(0.2, 0.35, 0.7), up);
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, HazeAgrees) {
  Cases cases;
  const double sigma0 = 3.912 / 40000.0;
  for (double z0 : {0.0, 2.0, 1500.0, 9000.0})
    for (double dz : {0.0, 1e-6, -1e-6, 0.004, 0.05, -0.05, 0.5, -1.0, 1.0})
      for (double distance : {1.0, 800.0, 60000.0, kFar}) {
        // The series and the difference of exponentials meet at |x| = 1e-2, where float's
        // difference has lost two digits; the scale is the depth of the level path.
        const double level = sigma0 * std::min(distance, 1e9) * std::exp(-z0 / 1200.0);
        cases.add("hazeDepth", &f::hazeDepth, std::max(level, 1e-12), sigma0, 1200.0, z0, dz,
                  distance);
      }
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, ShaftsAgree) {
  Cases cases;
  // Axis X, Y from the eye, radius, top; the eye inside, beside and far from the shaft.
  const glm::dvec4 shafts[] = {
      {0.0, 0.0, 800.0, 1500.0}, {3000.0, -200.0, 1200.0, 2000.0}, {4.0e4, 1.0e4, 2500.0, 1800.0}};
  const glm::dvec3 directions[] = {glm::normalize(glm::dvec3(1.0, 0.0, 0.0)),
                                   glm::normalize(glm::dvec3(1.0, -0.05, 0.1)),
                                   glm::normalize(glm::dvec3(0.97, 0.25, -0.02)),
                                   glm::normalize(glm::dvec3(0.0, 1e-5, 1.0)),
                                   glm::dvec3(0.0, 0.0, -1.0),
                                   glm::normalize(glm::dvec3(4.0, 1.0, 0.3))};
  const double sigma = 3.912 / 2000.0;
  for (const glm::dvec4& shaft : shafts)
    for (double z0 : {2.0, 900.0, 2500.0})
      for (const glm::dvec3& d : directions)
        for (double distance : {500.0, 2e4, kFar})
          cases.add("shaftDepth", &f::shaftDepth, sigma * 2.0 * shaft.z, shaft, sigma, z0, d,
                    distance);
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, AirMixingAgrees) {
  Cases cases;
  // No air, a trace of it (weighted / tau of two tiny numbers), thin, thick and capped air.
  const glm::dvec3 colour(0.9, 0.35, 0.02), air(0.55, 0.6, 0.7);
  for (double tau : {0.0, 1e-20, 1e-6, 0.02, 0.7, 6.0, 80.0, f::kOpaqueDepth})
    cases.add("airOver", &f::airOver, 1.0, colour, tau * air, tau);
  // Two media of different colours, the weights summed as applyAir sums them.
  const glm::dvec3 fog(0.8, 0.8, 0.82);
  for (double tau_fog : {0.0, 0.3, f::kOpaqueDepth})
    for (double tau_haze : {1e-9, 2.0, f::kOpaqueDepth})
      cases.add("airOver", &f::airOver, 1.0, glm::dvec3(0.0, 1.0, 0.5),
                tau_fog * fog + tau_haze * air, tau_fog + tau_haze);
  // A medium added to none and to others: thin, capped and endless (+infinity in C++, where
  // fogPathLength takes an endless path; 1e30 stands for it on the GPU, which caps it the same).
  for (const glm::dvec4& sum : {glm::dvec4(0.0), glm::dvec4(0.4, 0.45, 0.5, 0.8)})
    for (double tau : {0.0, 1e-7, 0.6, 999.0, 1e3, 1e30})
      cases.add("withMedium", &f::withMedium, 1e3, sum, tau, fog);
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, HeapLightAgrees) {
  Cases cases;
  // Clear, thin, thick and endless heaps; no forward scattering, the droplets' and nearly all.
  for (double tau : {0.0, 1e-7, 0.4, 25.0, 1e4, 1e30})
    for (double g : {0.0, 0.85, 0.999})
      cases.add("diffuseTransmittance", &f::diffuseTransmittance, 1.0, tau, g);
  // Faces turned to the light (no depth), grazing and turned away, past +-1 as rounding leaves
  // a dot product; chords of none, a heap's and a huge one.
  for (double chord : {0.0, 1500.0, 1e7})
    for (double n_dot_v : {-1.2, -1.0, -0.3, 0.0, 1e-6, 0.5, 1.0, 1.0000001})
      cases.add("heapDepth", &f::heapDepth, std::max(0.02 * chord, 1e-30), 0.02, chord, n_dot_v);
  for (double sun : {0.0, 1e-6, 0.8, 30.0, 1e3})
    for (double sky : {0.0, 4.0, 1e5}) cases.add("heapLight", &f::heapLight, 1.0, sun, sky, 0.85);
  // Normals bent towards gradients near, across and against them; gradients of a few metres'
  // envelope and of tiny and huge ones.
  const glm::dvec3 n = glm::normalize(glm::dvec3(0.3, -0.8, 0.5));
  for (const glm::dvec3& g : {glm::dvec3(0.2, -0.7, 0.6), glm::dvec3(1.0, 0.0, 0.0),
                              glm::dvec3(-0.3, 0.8, -0.45), glm::dvec3(0.0, 0.0, 1.0)})
    for (double size : {1e-12, 3e-3, 1.0, 1e6})
      for (double bend : {0.0, 0.6, 1.0})
        cases.add("bentNormal", &f::bentNormal, 1.0, n, size * g, bend);
  for (double n_dot_l : {-1.0, -0.6, -0.59, -0.2, 0.0, 0.45, 1.0})
    for (double wrap : {0.0, 0.6}) cases.add("skinDiffuse", &f::skinDiffuse, 1.0, n_dot_l, wrap);
  // Eq. 8 through a heap: in full light, its sun hidden, its sky hidden (K = 1/2), with and
  // without a highlight.
  for (const glm::dvec2& light : {glm::dvec2(1.0), glm::dvec2(0.0, 1.0), glm::dvec2(0.3, 0.5)})
    for (double highlight : {0.0, 0.7})
      cases.add("heapLitIntensity", &f::heapLitIntensity, 1.0, glm::dvec4(0.4, 0.5, 0.2, 8.0),
                light.x, light.y, 0.8, highlight, 0.55);
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, ShadingAgrees) {
  Cases cases;
  const glm::dvec4 terms[] = {{0.4, 0.5, 0.0, 8.0}, {0.25, 0.3, 0.6, 20.0}, {1.0, 0.0, 1.0, 1.0}};
  for (const glm::dvec4& t : terms)
    for (double diffuse : {0.0, 0.37, 1.0})
      cases.add("gardnerIntensity", &f::gardnerIntensity, 1.0, t, diffuse, 0.8, 0.55);
  const glm::dvec3 n = glm::normalize(glm::dvec3(0.2, -0.3, 1.0));
  const glm::dvec3 sun = glm::normalize(glm::dvec3(0.5, 0.4, 0.6));
  for (const glm::dvec3& view :
       {glm::normalize(glm::dvec3(-0.4, -0.2, 0.9)), glm::dvec3(0.0, 0.0, 1.0),
        glm::normalize(glm::dvec3(0.3, 0.1, -1.0))})
    for (double e : {1.0, 8.0, 64.0})
      cases.add("phongHighlight", &f::phongHighlight, 1.0, n, glm::dot(n, sun), sun, view, e);
  // Excess below, at and above the threshold; a hard threshold (D = 0).
  for (double excess : {-0.3, 0.0, 1e-7, 0.04, 0.2, 5.0})
    for (double d : {0.0, 0.1, 0.5}) cases.add("translucence", &f::translucence, 1.0, excess, d);
  for (double g : {0.0, 0.3, 1.0}) cases.add("limbExcess", &f::limbExcess, 1.0, 0.62, 0.35, 0.9, g);
  // llvmpipe's acos is good to about 2e-4 radians, which moves the mean by up to 1e-4.
  for (double c : {-1.5, -1.0, -0.6, 0.0, 0.3, 0.999, 1.0, 1.2})
    cases.add("sphereDiffuse", &f::sphereDiffuse, 10.0, c);
  // Normals facing the eye, away from it and across the ray.
  for (const glm::dvec3& ray : {glm::dvec3(0.0, 1.0, 0.0), glm::dvec3(-300.0, 50.0, -20.0)})
    for (const glm::dvec3& n :
         {glm::dvec3(0.0, -1.0, 0.0), glm::dvec3(0.6, 0.8, 0.0), glm::dvec3(0.0, 0.0, 1.0)})
      cases.add("facingViewer", &f::facingViewer, 1.0, n, ray);
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, SeaOpticsAgree) {
  Cases cases;
  for (double c : {-0.2, 0.0, 1e-4, 0.05, 0.5, 0.9, 1.0, 1.3})
    for (double n : {1.34, 1.2}) cases.add("fresnelWater", &f::fresnelWater, 0.02, c, n);
  // No whitecaps, all foam, and the blend of resolved and unresolved slopes (none resolved).
  for (double w : {0.0, 0.004, 0.3, 1.0})
    for (double var_unresolved : {0.0, 0.01, 0.03})
      cases.add("foamShare", &f::foamShare, 1.0, w, 0.05, 0.06, 0.03, var_unresolved);
  const glm::dvec3 sun = glm::normalize(glm::dvec3(0.3, 0.6, 0.5));
  const glm::dvec3 normals[] = {glm::dvec3(0.0, 0.0, 1.0),
                                glm::normalize(glm::dvec3(0.1, -0.2, 1.0))};
  for (const glm::dvec3& n : normals)
    for (const glm::dvec3& d :
         {glm::normalize(glm::dvec3(-0.3, -0.6, -0.5)), glm::normalize(glm::dvec3(0.2, -0.9, -0.1)),
          glm::normalize(glm::dvec3(0.0, 1.0, -0.001))})
      for (double slope_var : {0.003, 0.03}) {
        const double peak = f::glintRadiance(toFloat(glm::reflect(sun, n)), toFloat(sun),
                                             toFloat(n), toFloat(slope_var));
        cases.add("glintRadiance", &f::glintRadiance, peak, d, sun, n, slope_var);
      }
  // Facets level, tilted and steep enough to send a ray back down (the mirror held 0.01 above
  // level); rays steep, low and grazing.
  for (const glm::dvec2& slope : {glm::dvec2(0.0), glm::dvec2(0.1, -0.2), glm::dvec2(1e-7, 0.0),
                                  glm::dvec2(-3.0, 1.5), glm::dvec2(0.0, 40.0)}) {
    cases.add("seaNormal", &f::seaNormal, 1.0, slope);
    const glm::dvec3 n = f::seaNormal(slope);
    for (const glm::dvec3& d :
         {glm::dvec3(0.0, 0.0, -1.0), glm::normalize(glm::dvec3(0.3, 0.9, -0.2)),
          glm::normalize(glm::dvec3(0.0, 1.0, -1e-4)),
          glm::normalize(glm::dvec3(-0.5, -0.5, -0.7))}) {
      cases.add("seaIncidence", &f::seaIncidence, 1.0, d, n);
      cases.add("mirroredRay", &f::mirroredRay, 1.0, d, n, f::seaIncidence(toFloat(d), toFloat(n)));
    }
  }
  // Footprints near and far, steep and grazing (the floor of |sin|), a pixel of 1 mrad.
  for (double distance : {10.0, 3000.0, 4e4})
    for (double sin_elev : {-1.0, -0.05, -1e-3, -1e-6, 0.0})
      cases.add("seaFootprint", &f::seaFootprint,
                1e-3 * distance / std::sqrt(std::max(std::abs(sin_elev), 1e-4)), distance, sin_elev,
                1e-3);
  // The sines resolving none, some, the share's limit and more than all of the variance.
  for (double resolved : {0.0, 0.004, 0.02, 0.03, 0.5})
    cases.add("unresolvedSlopeVariance", &f::unresolvedSlopeVariance, 0.03, 0.03, resolved);
  // Water alone, foam alone, a mirror that hides the body, and the sun low.
  const glm::dvec3 body(0.002, 0.008, 0.035), sun_colour(1.0, 0.95, 0.85);
  for (const glm::dvec3& w : {glm::dvec3(0.8, 0.0, 0.02), glm::dvec3(0.8, 1.0, 0.02),
                              glm::dvec3(0.8, 0.3, 1.0), glm::dvec3(0.05, 0.1, 0.4)})
    cases.add("seaBodyAndFoam", &f::seaBodyAndFoam, 0.25, w.x, w.y, w.z, body, sun_colour);
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, ShadowsAgree) {
  Cases cases;
  for (double sunlight : {0.0, 1e-6, 0.45, 1.0})
    cases.add("groundLight", &f::groundLight, 1.0, sunlight);
  // Sun rays through a lobe's centre, off it, along its outline and missing it, from below it,
  // inside it and far below it; directions of unit and of other lengths (W is not a rotation).
  for (const glm::dvec3& o : {glm::dvec3(0.0, 0.0, -3.0), glm::dvec3(0.4, -0.2, 0.1),
                              glm::dvec3(1.0, 0.0, -2.0), glm::dvec3(2.5, 0.0, -40.0)})
    for (const glm::dvec3& w :
         {glm::dvec3(0.0, 0.0, 1.0), glm::dvec3(0.1, 0.05, 0.4), glm::dvec3(-0.8, 0.3, 2.5)})
      cases.add("sunRayLimb", &f::sunRayLimb, glm::dot(o, o) + 1.0, o, w);
  // Clear, thin, thick and endless chords; surfaces of no, some and full opacity.
  for (double opacity : {0.0, 0.3, 1.0})
    for (double depth : {0.0, 1e-6, 2.0, 1e4, 1e30})
      cases.add("lobeSunlight", &f::lobeSunlight, 1.0, opacity, depth, f::kDiffuseAsymmetry);
  // The sun's ray from a lobe's centre to the ground and from the ground up to a plane, the sun
  // high and low (the vector of any length).
  for (const glm::dvec3& to_sun : {glm::dvec3(0.3, -0.2, 0.93), glm::dvec3(2.0, 1.0, 0.05)})
    for (const glm::dvec4& p_at :
         {glm::dvec4(1200.0, -800.0, 1500.0, 0.0), glm::dvec4(-50.0, 30.0, 0.0, 4000.0)}) {
      const double reach =
          std::abs(p_at.w - p_at.z) * glm::length(glm::dvec2(to_sun.x, to_sun.y)) / to_sun.z +
          2000.0;
      cases.add("planeCrossing", &f::planeCrossing, reach, glm::dvec3(p_at), p_at.w, to_sun);
    }
  // Targets in sun and shade, facing the sun, grazing and turned away.
  for (double sunlight : {0.0, 0.4, 1.0})
    for (double n_dot_l : {-0.5, 0.0, 0.3, 1.0})
      cases.add("targetLight", &f::targetLight, 1.0, sunlight, n_dot_l);
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, VolumeAgrees) {
  Cases cases;
  // Back, side and forward scattering; no asymmetry, the default u = 0.8 and a strong one, and
  // g = 1, where the forward peak meets the base's floor. (Nearer g = 1 float's base loses its
  // digits to cancellation, which the tolerance would not cover.)
  for (double c : {-1.0, -0.4, 0.0, 0.5, 0.9, 1.0}) {
    cases.add("rayleighPhase", &f::rayleighPhase, 1.0, c);
    for (double g : {0.0, 0.3, 0.7485870751, 0.85, 1.0})
      cases.add("cornetteShanksPhase", &f::cornetteShanksPhase, 1.0, c, g);
  }
  // Lit, shaded (the difference below 0, held at 0) and sky-lit points.
  for (const glm::dvec3& sun :
       {glm::dvec3(0.9, 1.7, 0.0), glm::dvec3(0.4, 0.3, 0.6), glm::dvec3(0.0, 0.0, 1.0)})
    for (double phase : {0.0, 0.75, 40.0})
      cases.add("scatteredLight", &f::scatteredLight, phase + 3.0, phase, sun.x, sun.y, 0.35,
                sun.z);
  // Through the skin: backlit, side-lit and looking into the sun, with no beam left and all.
  for (double c : {-1.0, 0.2, 0.95})
    for (double sun : {0.0, 0.6})
      cases.add("forwardScattered", &f::forwardScattered, 1.0, sun, c, f::kDiffuseAsymmetry);
  // Steps of clear air, of thin and thick cloud, and of density rising, falling and huge.
  for (const glm::dvec2& rho : {glm::dvec2(0.0), glm::dvec2(0.1, 0.4), glm::dvec2(1.0, 0.0),
                                glm::dvec2(3.0, 5.0), glm::dvec2(1e6, 1e6)})
    for (double ds : {0.0, 25.0, 400.0})
      cases.add("segmentTransmittance", &f::segmentTransmittance, 1.0, rho.x, rho.y, ds, 16.33e-3);
  // A march's step, early and late, clear and opaque.
  for (double transmittance : {1.0, 0.3})
    for (double segment : {1.0, 0.6, 0.0})
      cases.add("stepScattered", &f::stepScattered, 2.0, transmittance, segment, 0.8, 1.7);
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, RegionsAndTermsAgree) {
  Cases cases;
  // Bands before, across and past their width; none (a step at kRegionMinBand).
  for (double x : {-5.0, 0.0, 1e-4, 200.0, 999.0, 4000.0})
    for (double width : {0.0, 1000.0}) cases.add("bandRamp", &f::bandRamp, 1.0, x, width);
  for (double heading : {0.0, 0.7, 3.0}) {
    const glm::dvec2 d(1234.5, -876.0);
    cases.add("regionAxes", &f::regionAxes, glm::length(d), d, std::cos(heading),
              std::sin(heading));
  }
  // Inside, on the edge band and outside a rectangle; each side of a front and none.
  for (const glm::dvec2& q : {glm::dvec2(0.0), glm::dvec2(4900.0, 100.0),
                              glm::dvec2(-300.0, 7950.0), glm::dvec2(6000.0, 0.0)})
    for (double side : {-1.0, 0.0, 1.0})
      cases.add("regionWeightAt", &f::regionWeightAt, 1.0, q, glm::dvec2(5000.0, 8000.0), 500.0,
                side, 2000.0);
  for (double t1 : {0.2, 0.99, 1.0, 1.5})
    for (double w : {0.0, 0.5, 1.0}) cases.add("regionThreshold", &f::regionThreshold, 1.0, t1, w);
  // Footprints from none to far past the lowest term, each removal of terms; the fade's
  // octave and the cut's steps.
  for (double footprint : {0.0, 1e-6, 0.01, 0.06, 0.1, 0.3, 2.0, 1e30})
    for (int removal : {f::kTermFade, f::kTermCut, f::kTermAll})
      cases.add("resolvedTerms", &f::resolvedTerms, 8.0, footprint, 8.0, removal);
  // Both sums above 0, one or both below (no cloud), and the texture's contrast k.
  for (const glm::dvec2& s : {glm::dvec2(0.7, 1.3), glm::dvec2(-0.2, 0.9), glm::dvec2(-1.0, -0.5)})
    for (double k : {0.5, 2.4}) cases.add("textureFromSums", &f::textureFromSums, 4.0, s.x, s.y, k);
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, FarDeckCoverAgrees) {
  Cases cases;
  // Rays straight up and down, steep, low and grazing (cot e up to 1e9, where the power's base
  // is raised to a huge exponent), level (the floor of |r.z|) and long; no cover, some, all.
  const glm::dvec3 rays[] = {{0.0, 0.0, 1.0},   {0.3, -0.2, -1.0}, {1.0, 0.5, 0.1},
                             {-0.7, 0.7, 0.01}, {1.0, 0.0, 1e-5},  {0.0, 1.0, 0.0},
                             {4e4, -3e4, 250.0}};
  for (const glm::dvec3& r : rays)
    for (double coverage : {0.0, 0.3, 0.92, 1.0, 1.4})
      for (double side_ratio : {0.0, 0.8, 2.5})
        cases.add("farApparentCover", &f::farApparentCover, 1.0, coverage, side_ratio, r);
  // A table's cell for values outside [0, 1], at its first, a middle and its last step, and
  // between steps: the far decks' 16 steps and the shadows' 32.
  for (double x : {-0.2, 0.0, 0.0625, 0.3, 0.5, 0.96875, 0.999, 1.0, 1.3})
    for (int steps : {f::kFarCoverSteps, 32}) cases.add("tableCell", &f::tableCell, 32.0, x, steps);
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, WavesAgree) {
  Cases cases;
  // Footprints from none to a kilometre's, wavelengths from the shortest drawn to the longest:
  // resolved, fading and lost.
  for (double footprint : {1e-6, 0.05, 3.0, 20.0, 1e3})
    for (double wavelength : {0.5, 83.0, 600.0})
      cases.add("waveResolved", &f::waveResolved, 1.0, wavelength, footprint);
  for (double w : {0.0, 0.3, 1.0})
    for (double amplitude : {1e-3, 1.2, 17.0})
      cases.add("waveHeightVariance", &f::waveHeightVariance, 0.5 * amplitude * amplitude, w,
                amplitude);
  // The shortest and the longest sines, at a crest, a slope and a trough of their phase and of
  // their modulation's, the modulation's wave vector across theirs.
  for (const glm::dvec2& k : {glm::dvec2(8.9, -8.9), glm::dvec2(0.02, 0.071)})
    for (double sin_phase : {-1.0, 0.0, 0.7})
      for (double cos_wobble : {-1.0, 0.3, 1.0}) {
        const glm::dvec2 q = 0.05 * glm::dvec2(-k.y, k.x);
        const double scale = 1.2 * (glm::length(k) + 2.5 * glm::length(q));
        cases.add("waveSlope", &f::waveSlope, scale, 1.0, 1.2, sin_phase, k, 2.5, cos_wobble, q);
      }
  expectAgree(cases);
}

TEST_F(SharedFormulaTest, EllipsoidAgrees) {
  Cases cases;
  // The eye near, far (1e4 radii: the difference of squares would lose every digit in float)
  // and level with the ellipsoid; rays through the middle, grazing, missing and turned away.
  const glm::dvec3 eyes[] = {{0.0, -3.0, 0.5}, {2.0, -1.0e4, 300.0}, {-1.5, 0.2, 0.0}};
  for (const glm::dvec3& o : eyes) {
    const double c = glm::dot(o, o) - 1.0;
    const glm::dvec3 to_centre = -o / glm::length(o);
    const glm::dvec3 across = glm::normalize(glm::cross(to_centre, glm::dvec3(0.3, 0.2, 1.0)));
    const double edge = 1.0 / glm::length(o);  // the tangent's offset per unit along
    for (double offset : {0.0, 0.5 * edge, 0.99 * edge, 1.01 * edge, 3.0 * edge}) {
      for (double length : {1.0, 250.0}) {
        const glm::dvec3 w = length * (to_centre + offset * across);
        const double delta = f::quarterDelta(toFloat(o), toFloat(w));
        cases.add("quarterDelta", &f::quarterDelta, glm::dot(w, w), o, w);
        if (delta > 1e-3 * glm::dot(w, w))
          cases.add("unitSphereRoots", &f::unitSphereRoots, glm::length(o) / length, o, w, c,
                    delta);
      }
    }
  }
  // Chords from inside, on and outside the unit sphere, along, across and away from it.
  for (const glm::dvec3& o : {glm::dvec3(0.0), glm::dvec3(0.6, 0.0, 0.8),
                              glm::dvec3(0.2, -0.3, 0.1), glm::dvec3(0.0, -2.5, 0.0)})
    for (const glm::dvec3& w : {glm::dvec3(0.0, 1.0, 0.0), glm::dvec3(0.0, 0.0, 0.4),
                                glm::dvec3(-0.6, 0.0, -0.8), glm::dvec3(1.0, 0.0, 0.0)})
      cases.add("unitSphereChord", &f::unitSphereChord, 2.0 / glm::length(w), o, w);
  // The limb function of a sphere seen from 3 radii along -y: axis +y, P = (I - a a^T) / 8.
  const glm::dvec3 axis(0.0, 1.0, 0.0);
  const glm::dvec3 p0(1.0 / 8.0, 0.0, 0.0), p1(0.0, 0.0, 0.0), p2(0.0, 0.0, 1.0 / 8.0);
  for (const glm::dvec3& d :
       {glm::dvec3(0.0, 1.0, 0.0), glm::dvec3(0.1, 1.0, -0.2), glm::dvec3(0.35, 1.0, 0.0),
        glm::dvec3(0.5, 1.0, 0.3), glm::dvec3(0.0, -1.0, 0.0), glm::dvec3(1.0, 0.0, 0.0)})
    cases.add("limbFunction", &f::limbFunction, 1.0, d, axis, p0, p1, p2);
  expectAgree(cases);
}

}  // namespace
}  // namespace nephele
