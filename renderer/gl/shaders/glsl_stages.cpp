// glsl_stages: the tool of the glsl_stages test (tests/CMakeLists.txt). It assembles the GL
// renderer's stages as the renderer does, across the variants their layouts and #defines
// select, writes each complete stage to a file of DIRECTORY (.vert or .frag) and checks them
// all with glslangValidator, which knows nothing of Mesa: a stage it rejects is reported with
// the layout that made it.
//
//   glsl_stages VALIDATOR DIRECTORY
//
// The sky, clipmap and ellipsoid stages come from the renderer's own source functions
// (sky_shaders.h, ellipsoid_shaders.h) and the shadow map's from ShadowMap. The
// automaton, target and floor programs are assembled inside their renderers' classes; here
// their few prefix lines are written out again, next to the pieces those classes join
// (automaton_renderer.cpp, target_renderer.cpp, gl_renderer.cpp).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include "renderer/gl/ellipsoid_shaders.h"
#include "renderer/gl/shaders/automaton_glsl.h"
#include "renderer/gl/shaders/floor_glsl.h"
#include "renderer/gl/shaders/target_glsl.h"
#include "renderer/gl/shadow_map.h"
#include "renderer/gl/sky_shaders.h"
#include "world/scene.h"

namespace nephele {
namespace {

struct Stage {
  std::string name;  // the file name, with the stage's extension
  std::string source;
};

class Stages {
 public:
  // Adds a stage unless the same text is already listed under another name.
  void add(const std::string& name, bool vertex, const std::string& source) {
    if (!seen_.insert(source).second) return;
    std::string file = name;
    for (char& c : file)
      if (c == '/') c = '_';
    stages_.push_back({file + (vertex ? ".vert" : ".frag"), source});
  }
  const std::vector<Stage>& all() const { return stages_; }

 private:
  std::set<std::string> seen_;
  std::vector<Stage> stages_;
};

const TermFilter kFilters[] = {TermFilter::kFade, TermFilter::kCut, TermFilter::kNone};

// The switch combinations to try with `count` switches: all of them where `all`, else none
// and every one.
std::vector<int> switchSets(int count, bool all) {
  if (all) {
    std::vector<int> sets;
    for (int bits = 0; bits < 1 << count; ++bits) sets.push_back(bits);
    return sets;
  }
  return {0, (1 << count) - 1};
}

void addSky(Stages& stages) {
  stages.add("polygon", true, polygonVertexSource());
  stages.add("clipmap_bake", false, clipmapBakeSource());
  using K = LayerKind;
  // Layer sets: every kind above, below and casting; none; one of each kind in each place.
  std::vector<SkyPassLayout> sets(1);
  sets[0].above = {K::kBakedGardner, K::kClipmapGardner, K::kTable};
  sets[0].below = {K::kProceduralGardner, K::kBakedGardner};
  sets[0].casters = {K::kClipmapGardner, K::kProceduralGardner, K::kTable, K::kBakedGardner};
  sets.emplace_back();
  for (K kind : {K::kBakedGardner, K::kProceduralGardner, K::kTable, K::kClipmapGardner}) {
    sets.emplace_back().above = {kind};
    sets.emplace_back().below = {kind};
    sets.emplace_back().casters = {kind};
  }
  // Every combination of the seven switches for the first set; none and all for the others.
  for (std::size_t k = 0; k < sets.size(); ++k)
    for (TermFilter filter : kFilters)
      for (int bits : switchSets(7, k == 0)) {
        SkyPassLayout layout = sets[k];
        layout.term_filter = filter;
        layout.background = bits & 1;
        layout.air = (bits & 2) ? kEveryAirMedium : 0u;
        layout.specular = bits & 4;
        layout.targets = bits & 8;
        layout.regions = bits & 16;
        layout.shadows = bits & 32;
        layout.sea = bits & 64;
        stages.add("sky_" + layout.key(), false, skyFragmentSource(layout));
      }
}

void addEllipsoids(Stages& stages) {
  using P = EllipsoidProgram;
  using T = SolidTextureKind;
  // Every program and shading rate, with every combination of the five switches for the
  // default texture and filter, none and all for the others.
  for (P program : {P::kFusedCentre, P::kFusedPerPixel, P::kFusedSamples, P::kFusedBlend,
                    P::kFusedRest, P::kFusedResolve, P::kTileThreshold, P::kTileLimb,
                    P::kTileColour, P::kTileComposite, P::kVeil, P::kImpostor})
    for (int rate : {1, 2, 4})
      for (T texture : {T::kBakedGardner, T::kProcedural, T::kTable})
        for (TermFilter filter : kFilters)
          for (int bits :
               switchSets(5, texture == T::kBakedGardner && filter == TermFilter::kFade)) {
            EllipsoidPassLayout layout;
            layout.program = program;
            layout.texture = texture;
            layout.term_filter = filter;
            layout.shading_rate = rate;
            layout.spotlight = bits & 1;
            layout.air = (bits & 2) ? kEveryAirMedium : 0u;
            layout.specular = bits & 4;
            layout.targets = bits & 8;
            // The renderer asks for the history with kFusedPerPixel only: kFusedSamples writes
            // its distance where the history would go (location 1).
            layout.history = (bits & 16) && program == P::kFusedPerPixel;
            const std::string key = "ellipsoid_" + layout.key();
            stages.add(key, true, ellipsoidVertexSource(layout));
            stages.add(key, false, ellipsoidFragmentSource(layout));
          }
}

void addOthers(Stages& stages) {
  // AutomatonRenderer::program: its #defines, MAX_STEPS (kMaxMarchSteps), the view chunk.
  for (int bits = 0; bits < 8; ++bits) {
    std::string defines;
    if (bits & 1) defines += airDefines(kEveryAirMedium);
    if (bits & 2) defines += "#define TARGETS\n";
    if (bits & 4) defines += "#define CORNETTE_SHANKS\n";
    stages.add("automaton_" + std::to_string(bits), false,
               "#version 450 core\n" + defines + "#define MAX_STEPS 2048\n" + viewShaderSource() +
                   glsl::automaton::kVolumePass);
  }
  // ShadowMap::prepare.
  stages.add("shadow_map", true, ShadowMap::vertexSource());
  stages.add("shadow_map", false, ShadowMap::fragmentSource());
  // TargetRenderer::program.
  stages.add("target", true, glsl::target::kVertex);
  stages.add("target", false,
             "#version 450 core\n" + airDefines(kEveryAirMedium) + viewShaderSource() +
                 glsl::target::kFragment);
  // GlRenderer::renderFloor.
  stages.add("floor", false, glsl::floor_pass::kFloorFragment);
}

// Runs the validator on `files` and returns whether it accepted them all.
bool validate(const std::string& validator, const std::vector<std::string>& files) {
  std::string command = "'" + validator + "'";
  for (const std::string& file : files) command += " '" + file + "'";
  command += " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) {
    std::cerr << "glsl_stages: cannot run " << validator << "\n";
    return false;
  }
  std::string output;
  char buffer[4096];
  while (std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
  const int status = pclose(pipe);
  if (status == 0) return true;
  // The validator names every file and prints errors under the one they belong to.
  std::cerr << output;
  return false;
}

}  // namespace
}  // namespace nephele

int main(int argc, char** argv) {
  using namespace nephele;
  if (argc != 3) {
    std::cerr << "usage: glsl_stages VALIDATOR DIRECTORY\n";
    return 2;
  }
  const std::string validator = argv[1];
  const std::filesystem::path directory = argv[2];
  std::filesystem::remove_all(directory);
  std::filesystem::create_directories(directory);

  Stages stages;
  addSky(stages);
  addEllipsoids(stages);
  addOthers(stages);

  std::vector<std::string> files;
  for (const Stage& stage : stages.all()) {
    const std::filesystem::path path = directory / stage.name;
    std::ofstream(path, std::ios::binary) << stage.source;
    files.push_back(path.string());
  }
  // The validator starts once per batch (its start costs more than most stages).
  constexpr std::size_t kBatch = 200;
  int failed_batches = 0;
  for (std::size_t first = 0; first < files.size(); first += kBatch) {
    const std::vector<std::string> batch(
        files.begin() + std::ptrdiff_t(first),
        files.begin() + std::ptrdiff_t(std::min(files.size(), first + kBatch)));
    if (!validate(validator, batch)) ++failed_batches;
  }
  std::cout << stages.all().size() << " stages in " << directory.string() << ": "
            << (failed_batches == 0 ? "all valid" : "some rejected (above)") << "\n";
  return failed_batches == 0 ? 0 : 1;
}
