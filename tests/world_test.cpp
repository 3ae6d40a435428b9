#include "world/world.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "world/formations/weather.h"
#include "world/limits.h"
#include "world/textures/layer_texture.h"

namespace nephele {
namespace {

// A small world with every kind of cloud, wind shear and development schedules.
std::pair<Scene, WorldDynamics> smallWorld() {
  Scene scene;
  scene.layers.push_back({});
  scene.layers[0].altitude_m = 4000.0;
  scene.clouds.push_back({});
  scene.clouds[0].ellipsoids.push_back({});
  WorldDynamics d;
  d.wind.samples = {{0.0, {2.0, 0.0}}, {3000.0, {12.0, -4.0}}};
  d.layers.push_back({});
  d.layers[0].threshold = {{0.0, 1200.0}, {0.9, 0.1}};
  d.clouds.push_back({});
  d.clouds[0].transition = {{0.0, 60.0}, {0.3, 0.1}};
  AutomatonCloudSpec a;
  a.name = "test";
  a.cells = {12, 10, 8};
  a.cell_size_m = 50.0;
  a.step_interval_s = 1.5;
  a.warmup_steps = 15;
  a.position = {0.0, 0.0, 1000.0};
  d.automata.push_back(a);
  return {scene, d};
}

World makeWorld(int threads = 1) {
  auto [scene, dynamics] = smallWorld();
  return World(scene, dynamics, threads);
}

TEST(World, OneLongAdvanceEqualsManyShortOnes) {
  World once = makeWorld(), split = makeWorld(), irregular = makeWorld();
  ASSERT_EQ(once.advance(10.0), "");
  for (int i = 0; i < 100; ++i) ASSERT_EQ(split.advance(0.1), "");
  for (double dt : {0.0, 1e-9, 3.3, 0.7 - 1e-9, 6.0}) ASSERT_EQ(irregular.advance(dt), "");
  EXPECT_EQ(once.timeNs(), 10'000'000'000);
  EXPECT_EQ(once.hash(), split.hash());
  EXPECT_EQ(once.hash(), irregular.hash());
  EXPECT_GT(once.automatonStepsRun(), 0u);
  const Scene a = once.scene(), b = split.scene();
  EXPECT_EQ(a.clouds[0].ellipsoids[0].centre, b.clouds[0].ellipsoids[0].centre);
  EXPECT_EQ(a.automata[0].corner, b.automata[0].corner);
  EXPECT_EQ(a.automata[0].blend, b.automata[0].blend);
}

TEST(World, RunsAreIdenticalWhateverTheThreadCount) {
  World one = makeWorld(1), two = makeWorld(2);
  ASSERT_EQ(one.advance(30.0), "");
  ASSERT_EQ(two.advance(30.0), "");
  EXPECT_EQ(one.hash(), two.hash());
}

TEST(World, TinyZeroAndHourLongStepsStayFinite) {
  World w = makeWorld();
  const std::uint64_t start = w.hash();
  ASSERT_EQ(w.advance(0.0), "");
  EXPECT_EQ(w.hash(), start);
  ASSERT_EQ(w.advance(1e-9), "");
  EXPECT_EQ(w.timeNs(), 1);
  ASSERT_EQ(w.advance(3600.0), "");
  const Scene s = w.scene();
  ASSERT_EQ(s.automata.size(), 1u);
  const AutomatonCloudView& v = s.automata[0];
  for (float rho : v.to->lattice.density) ASSERT_TRUE(std::isfinite(rho) && rho >= 0.0f);
  for (float t : v.to->lattice.sunlight) ASSERT_TRUE(t >= 0.0f && t <= 1.0f);
  EXPECT_TRUE(v.blend >= 0.0 && v.blend <= 1.0);
  // After an hour the grid has drifted with the wind at its middle (1200 m: 6 m/s east).
  EXPECT_NEAR(v.corner.x - (-300.0), 3600.0 * (2.0 + 10.0 * 1200.0 / 3000.0), 1e-6);
}

TEST(World, RejectsBadStepsAndChangesNothing) {
  World w = makeWorld();
  const std::uint64_t start = w.hash();
  EXPECT_NE(w.advance(-1.0).find("dt"), std::string::npos);
  EXPECT_NE(w.advance(std::nan("")), "");
  EXPECT_NE(w.advance(INFINITY), "");
  EXPECT_EQ(w.hash(), start);
}

TEST(World, RefusesToRunItsClockPastItsLimit) {
  World w(Scene{}, WorldDynamics{});
  std::string error;
  int advances = 0;
  while (error.empty() && advances < 2000) {
    error = w.advance(Limits::kMaxAdvance);
    ++advances;
  }
  EXPECT_THAT(error, ::testing::HasSubstr("limit"));
  EXPECT_EQ(advances, 923);  // 2^63 ns is 922.3 advances of 1e7 s
  EXPECT_GT(w.timeNs(), 0);
}

// A scene may start later than one advance reaches: the pieces land on the same nanosecond
// as the whole, and a span beyond the latest start is refused with nothing changed.
TEST(World, LongSpansAdvanceInPieces) {
  World w(Scene{}, WorldDynamics{});
  int calls = 0, of = 0;
  const double span = 2.5e7 + 0.123456789;
  const std::int64_t whole = std::llround(span / World::kTimeResolutionS);
  ASSERT_EQ(w.advanceInPieces(span, 3, [&](int, int n) { ++calls, of = n; }), "");
  EXPECT_EQ(w.timeNs(), whole);
  EXPECT_EQ(calls, 3);
  EXPECT_EQ(of, 3);
  EXPECT_THAT(w.advanceInPieces(Limits::kMaxTime * 2), ::testing::HasSubstr("allowed: 0 to"));
  EXPECT_EQ(w.timeNs(), whole);
}

TEST(World, DevelopmentSchedulesAndDriftFollowTime) {
  World w = makeWorld();
  ASSERT_EQ(w.advance(600.0), "");
  const Scene s = w.scene();
  EXPECT_NEAR(s.layers[0].threshold, 0.5, 1e-12);   // halfway from 0.9 to 0.1
  EXPECT_NEAR(s.clouds[0].transition, 0.1, 1e-12);  // held after its last keyframe
  // The layer at 4000 m drifts with the wind held above 3000 m.
  EXPECT_EQ(s.layers[0].texture.drift_velocity, glm::dvec2(12.0, -4.0));
  // The ellipsoid (centre at 1500 m) moves with the wind there and carries its texture along.
  const glm::dvec2 wind(2.0 + 10.0 * 0.5, -4.0 * 0.5);
  EXPECT_NEAR(s.clouds[0].drift_m.x, 600.0 * wind.x, 1e-9);
  EXPECT_NEAR(s.clouds[0].ellipsoids[0].centre.y, 600.0 * wind.y, 1e-9);
}

TEST(World, DensityChangesSmoothlyBetweenAutomatonSteps) {
  World w = makeWorld();
  ASSERT_EQ(w.advance(3.0), "");  // exactly on a step boundary (1.5 s interval)
  auto densityAt = [&](const World& world) {
    const AutomatonCloudView v = world.scene().automata[0];
    return v.exactDensity(v.corner + glm::dvec3(300.0, 250.0, 200.0));
  };
  double previous = densityAt(w);
  double largest_jump = 0.0, total_change = 0.0;
  for (int i = 0; i < 60; ++i) {  // 6 s in 0.1 s ticks: four automaton steps
    ASSERT_EQ(w.advance(0.1), "");
    const double now = densityAt(w);
    largest_jump = std::max(largest_jump, std::abs(now - previous));
    total_change += std::abs(now - previous);
    previous = now;
  }
  // Linear blending spreads each step's change over 15 ticks.
  EXPECT_GT(total_change, 0.0);
  EXPECT_LE(largest_jump, total_change / 4.0 + 1e-12);
}

TEST(World, LightIsRecomputedOnlyWhenTheSunMoves) {
  World w = makeWorld();
  const auto before = w.scene().automata[0].to;
  Sun sun = w.base().sun;
  w.setSun(sun);
  EXPECT_EQ(w.scene().automata[0].to, before);  // same keyframe object: no relighting
  sun.elevation_deg = 10.0;
  w.setSun(sun);
  const auto after = w.scene().automata[0].to;
  EXPECT_NE(after, before);
  EXPECT_EQ(after->lattice.density, before->lattice.density);
  EXPECT_NE(after->lattice.sunlight, before->lattice.sunlight);
}

TEST(World, WithoutAutomatonCloudsNoAutomatonWorkIsDone) {
  auto [scene, dynamics] = smallWorld();
  dynamics.automata.clear();
  World w(scene, dynamics);
  ASSERT_EQ(w.advance(100.0), "");
  EXPECT_EQ(w.automatonStepsRun(), 0u);
  EXPECT_TRUE(w.scene().automata.empty());
}

TEST(World, SnapshotRestoresBitExactlyAndContinuesIdentically) {
  auto [scene, dynamics] = smallWorld();
  scene.haze = Haze{25000.0, 900.0};
  World original(scene, dynamics, 1);
  ASSERT_EQ(original.advance(12.3), "");
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / "nephele_world_test.snapshot";
  ASSERT_EQ(original.saveSnapshot(path.string()), "");
  // Restore into a world built from a different scene.
  World restored(Scene{}, WorldDynamics{});
  ASSERT_EQ(restored.restoreSnapshot(path.string()), "");
  EXPECT_EQ(restored.hash(), original.hash());
  EXPECT_EQ(restored.timeNs(), original.timeNs());
  ASSERT_TRUE(restored.base().haze);
  EXPECT_EQ(restored.base().haze->scale_height_m, 900.0);
  EXPECT_EQ(restored.scene().automata[0].to->lattice.sunlight,
            original.scene().automata[0].to->lattice.sunlight);
  ASSERT_EQ(original.advance(20.0), "");
  ASSERT_EQ(restored.advance(20.0), "");
  EXPECT_EQ(restored.hash(), original.hash());
  std::filesystem::remove(path);
}

TEST(World, ARecentringThatWouldCarryATargetOutOfRangeIsRefusedAndChangesNothing) {
  // Issue 62: a view or target near the edge of the range its readers accept, then a set_site
  // whose re-centring (about 111 km north-south) would carry it past the edge.
  World world = makeWorld();
  ASSERT_EQ(world.setSite({46.0, 7.0, 0.0}), "");
  Target edge;
  edge.name = "edge";
  edge.centre = {0.0, Limits::kMaxCoordinate - 10000.0, 100.0};
  ASSERT_EQ(world.addTarget(edge, false, 4), "");
  const std::uint64_t hash = world.hash();
  const Site south{45.0, 7.0, 0.0};
  EXPECT_GT(glm::length(world.recentreShift(south)), 100000.0);
  EXPECT_THAT(world.setSiteError(south), ::testing::HasSubstr("target edge"));
  EXPECT_THAT(world.setSite(recentred(*world.base().site, 45.0, 7.0).to),
              ::testing::HasSubstr("nothing changed"));
  EXPECT_EQ(world.hash(), hash);
  // A weather layer's macrocluster likewise.
  World clustered = makeWorld();
  ASSERT_EQ(clustered.setSite({46.0, 7.0, 0.0}), "");
  WeatherLayer patch = typicalWeatherLayer(CloudType::kStratus, 0.6);
  patch.region.centre = {0.0, Limits::kMaxCoordinate - 10000.0};
  patch.region.half_size = {5000.0, 5000.0};
  ASSERT_EQ(clustered.setWeather({2, std::nullopt}, patch), "");
  EXPECT_THAT(clustered.setSiteError(south), ::testing::HasSubstr("weather layer 2"));
  // The other way the target moves inward: allowed, and the state saves and reads back.
  ASSERT_EQ(world.setSite(recentred(*world.base().site, 47.0, 7.0).to), "");
  const std::vector<std::uint8_t> bytes = world.snapshot();
  World restored = makeWorld();
  EXPECT_EQ(restored.restore(bytes), "");
  EXPECT_EQ(restored.hash(), world.hash());
}

TEST(World, AMacroclusterCarriedFarByTheWindSavesAndReadsBack) {
  // Issue 62's live fuzz: a weather layer with a macrocluster, set again after 1e7 s of a
  // 150 m/s wind, holds its field's and layer's regions 1.5e9 m out in their drifting frames;
  // the snapshot reader refused them as if a host had placed them there.
  auto [scene, dynamics] = smallWorld();
  dynamics.automata.clear();  // a day of automaton steps is not what this test is about
  World world(scene, dynamics, 1);
  ASSERT_EQ(world.setWind({{{0.0, {150.0, 0.0}}}}), "");
  for (CloudType type : {CloudType::kCumulus, CloudType::kStratus}) {
    WeatherLayer w = typicalWeatherLayer(type, 0.5);
    w.region.centre = {1000.0, -2000.0};
    w.region.half_size = {20000.0, 20000.0};
    const WeatherKey key{type == CloudType::kCumulus ? 1 : 2, std::nullopt};
    ASSERT_EQ(world.setWeather(key, w), "");
  }
  ASSERT_EQ(world.advance(Limits::kMaxAdvance), "");
  for (CloudType type : {CloudType::kCumulus, CloudType::kStratus}) {
    WeatherLayer w = typicalWeatherLayer(type, 0.6);
    w.region.centre = {1000.0, -2000.0};
    w.region.half_size = {20000.0, 20000.0};
    ASSERT_EQ(world.setWeather({type == CloudType::kCumulus ? 1 : 2, std::nullopt}, w), "");
  }
  World restored(Scene{}, WorldDynamics{});
  EXPECT_EQ(restored.restore(world.snapshot()), "");
  EXPECT_EQ(restored.hash(), world.hash());
}

TEST(World, ASnapshotThatWouldNotReadBackIsNotInstalled) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / "nephele_world_test_proven.snapshot";
  World good = makeWorld();
  ASSERT_EQ(good.saveSnapshot(path.string()), "");
  // A world holding what no reader accepts (built directly, past every request's checks): its
  // snapshot is written, fails to read back, and is not installed.
  auto [scene, dynamics] = smallWorld();
  Target far;
  far.name = "far";
  far.centre = {2.0 * Limits::kMaxCoordinate, 0.0, 0.0};
  scene.targets.push_back(far);
  World bad(scene, dynamics, 1);
  const std::string error = bad.saveSnapshot(path.string());
  EXPECT_THAT(error, ::testing::HasSubstr("does not read back"));
  EXPECT_THAT(error, ::testing::HasSubstr("target far"));
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".partial"));
  World restored(Scene{}, WorldDynamics{});
  ASSERT_EQ(restored.restoreSnapshot(path.string()), "");
  EXPECT_EQ(restored.hash(), good.hash());  // the previous snapshot stayed
  std::filesystem::remove(path);
}

TEST(World, CorruptOrTruncatedSnapshotsAreRefusedAndLeaveTheWorldAsItWas) {
  World source = makeWorld();
  ASSERT_EQ(source.advance(5.0), "");
  const std::vector<std::uint8_t> good = source.snapshot();
  World target = makeWorld();
  const std::uint64_t before = target.hash();
  auto refused = [&](std::vector<std::uint8_t> bytes, const std::string& expected) {
    const std::string error = target.restore(bytes);
    EXPECT_NE(error.find(expected), std::string::npos) << error;
    EXPECT_EQ(target.hash(), before);
  };
  std::vector<std::uint8_t> flipped = good;
  flipped[flipped.size() / 2] ^= 0x10;
  refused(flipped, "corrupt");
  refused({good.begin(), good.end() - 100}, "truncated");
  refused({good.begin(), good.begin() + 10}, "not a Nephele snapshot");
  std::vector<std::uint8_t> version = good;
  version[8] = 99;
  refused(version, "format version");
  refused({}, "not a Nephele snapshot");
  EXPECT_NE(target.restoreSnapshot("/nonexistent/dir/x.snapshot").find("cannot read"),
            std::string::npos);
  EXPECT_EQ(target.hash(), before);
  ASSERT_EQ(target.restore(good), "");
  EXPECT_EQ(target.hash(), source.hash());
}

// Issue 31, item 2: a snapshot whose clouds hold more ellipsoids than the world budget is
// refused (a daemon restarted with a lower `[world] max_ellipsoids`), the world unchanged.
TEST(World, SnapshotsBeyondTheWorldBudgetAreRefused) {
  World source = makeWorld();
  const std::size_t held = ellipsoidCount(source.base());
  ASSERT_GE(held, 1u);
  const std::vector<std::uint8_t> bytes = source.snapshot();
  World target = makeWorld();
  ASSERT_EQ(target.advance(1.0), "");
  const std::uint64_t before = target.hash();
  const std::string error = target.restore(bytes, held - 1);
  EXPECT_TRUE(error.starts_with(World::kOverBudget)) << error;
  EXPECT_NE(error.find(std::to_string(held) + " ellipsoids"), std::string::npos) << error;
  EXPECT_EQ(target.hash(), before);
  ASSERT_EQ(target.restore(bytes, held), "");
  EXPECT_EQ(target.hash(), source.hash());
}

// Issue 12, case 1: restoring from a directory, a FIFO (no writer), a 1 GiB sparse file or a
// file longer than its header says is refused at once with a message, reads at most the
// header, and leaves the world as it was.
TEST(World, RestoreRefusesWhatIsNotASnapshotFileWithoutReadingIt) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("nephele_restore_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "a_directory");
  const std::string fifo = (dir / "a_fifo").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string sparse = (dir / "sparse").string();
  {
    std::ofstream(sparse).close();
    std::filesystem::resize_file(sparse, std::uintmax_t(1) << 30);
  }
  World source = makeWorld();
  const std::string padded = (dir / "padded").string();
  ASSERT_EQ(source.saveSnapshot(padded), "");
  std::ofstream(padded, std::ios::app) << "trailing";

  World target = makeWorld();
  const std::uint64_t before = target.hash();
  EXPECT_THAT(target.restoreSnapshot((dir / "a_directory").string()),
              ::testing::HasSubstr("not a regular file"));
  EXPECT_THAT(target.restoreSnapshot(fifo), ::testing::HasSubstr("not a regular file"));
  EXPECT_THAT(target.restoreSnapshot(sparse), ::testing::HasSubstr("not a Nephele snapshot"));
  EXPECT_THAT(target.restoreSnapshot(padded), ::testing::HasSubstr("header promises"));
  EXPECT_EQ(target.hash(), before);
  std::filesystem::remove_all(dir);
}

TEST(World, AWindChangeKeepsCloudsAndLayersWhereTheyAre) {
  World world = makeWorld();
  ASSERT_EQ(world.advance(100.0), "");
  const Scene before = world.scene();
  const LayerTexture layer_before(before.layers[0].texture);
  ASSERT_EQ(world.setWind({{{0.0, {-20.0, 5.0}}}}), "");
  const Scene now = world.scene();
  const LayerTexture layer_now(now.layers[0].texture);
  const glm::dvec3 c0 = before.clouds[0].ellipsoids[0].centre;
  EXPECT_NEAR(glm::length(now.clouds[0].ellipsoids[0].centre - c0), 0.0, 1e-9);
  EXPECT_NEAR(glm::length(now.clouds[0].drift_m - before.clouds[0].drift_m), 0.0, 1e-9);
  EXPECT_NEAR(glm::length(layer_now.driftOffset(100.0) - layer_before.driftOffset(100.0)), 0.0,
              1e-6);
  // ... and from then on they drift with the new wind.
  ASSERT_EQ(world.advance(10.0), "");
  const glm::dvec3 moved = world.scene().clouds[0].ellipsoids[0].centre - c0;
  EXPECT_NEAR(moved.x, -200.0, 1e-6);
  EXPECT_NEAR(moved.y, 50.0, 1e-6);
}

// An automaton cloud too stays where its drift has brought it and rides the new wind, in the
// world and in a snapshot taken after the change.
TEST(World, AWindChangeKeepsAutomataWhereTheyAreAndSnapshotsKeepIt) {
  World world = makeWorld();
  ASSERT_EQ(world.advance(3.0), "");
  const glm::dvec3 corner = world.scene().automata[0].corner;
  ASSERT_EQ(world.setWind({{{0.0, {-20.0, 5.0}}}}), "");
  EXPECT_NEAR(glm::length(world.scene().automata[0].corner - corner), 0.0, 1e-9);
  ASSERT_EQ(world.advance(10.0), "");
  const glm::dvec3 moved = world.scene().automata[0].corner - corner;
  EXPECT_NEAR(moved.x, -200.0, 1e-6);
  EXPECT_NEAR(moved.y, 50.0, 1e-6);
  World restored(Scene{}, WorldDynamics{});
  ASSERT_EQ(restored.restore(world.snapshot()), "");
  EXPECT_EQ(restored.hash(), world.hash());
  EXPECT_EQ(restored.scene().automata[0].corner, world.scene().automata[0].corner);
  ASSERT_EQ(world.advance(4.5), "");
  ASSERT_EQ(restored.advance(4.5), "");
  EXPECT_EQ(restored.scene().automata[0].corner, world.scene().automata[0].corner);
  EXPECT_EQ(restored.scene().automata[0].to->lattice.density,
            world.scene().automata[0].to->lattice.density);
  EXPECT_EQ(restored.hash(), world.hash());
}

// Every member of two scenes that the world's time or its edits set, compared bit for bit.
void expectSameScene(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.time_s, b.time_s);
  EXPECT_EQ(a.camera.position, b.camera.position);
  EXPECT_EQ(a.sun.elevation_deg, b.sun.elevation_deg);
  EXPECT_EQ(a.fog, b.fog);
  EXPECT_EQ(a.haze, b.haze);
  EXPECT_EQ(a.sea, b.sea);
  EXPECT_EQ(a.site, b.site);
  EXPECT_EQ(a.content_origin, b.content_origin);
  EXPECT_EQ(a.weather, b.weather);
  ASSERT_EQ(a.layers.size(), b.layers.size());
  for (std::size_t i = 0; i < a.layers.size(); ++i) {
    const CloudLayer &x = a.layers[i], &y = b.layers[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.threshold, y.threshold);
    EXPECT_EQ(x.transition, y.transition);
    EXPECT_EQ(x.texture.drift_offset_m, y.texture.drift_offset_m);
    EXPECT_EQ(x.texture.drift_velocity, y.texture.drift_velocity);
    EXPECT_EQ(x.texture.gardner.t0, y.texture.gardner.t0);
    EXPECT_EQ(x.region, y.region);
  }
  ASSERT_EQ(a.clouds.size(), b.clouds.size());
  for (std::size_t i = 0; i < a.clouds.size(); ++i) {
    const EllipsoidCloud &x = a.clouds[i], &y = b.clouds[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.drift_m, y.drift_m);
    EXPECT_EQ(x.threshold_centre, y.threshold_centre);
    EXPECT_EQ(x.threshold_limb, y.threshold_limb);
    EXPECT_EQ(x.transition, y.transition);
    EXPECT_EQ(x.colour, y.colour);
    ASSERT_EQ(x.ellipsoids.size(), y.ellipsoids.size());
    for (std::size_t k = 0; k < x.ellipsoids.size(); ++k)
      EXPECT_EQ(x.ellipsoids[k].centre, y.ellipsoids[k].centre);
  }
  ASSERT_EQ(a.fields.size(), b.fields.size());
  for (std::size_t i = 0; i < a.fields.size(); ++i) {
    EXPECT_EQ(a.fields[i].name, b.fields[i].name);
    EXPECT_EQ(a.fields[i].drift_m, b.fields[i].drift_m);
    EXPECT_EQ(a.fields[i].shear, b.fields[i].shear);
    EXPECT_EQ(a.fields[i].region, b.fields[i].region);
  }
  ASSERT_EQ(a.targets.size(), b.targets.size());
  for (std::size_t i = 0; i < a.targets.size(); ++i) {
    EXPECT_EQ(a.targets[i].name, b.targets[i].name);
    EXPECT_EQ(a.targets[i].centre, b.targets[i].centre);
    EXPECT_EQ(a.targets[i].orientation.heading_deg, b.targets[i].orientation.heading_deg);
  }
  ASSERT_EQ(a.automata.size(), b.automata.size());
  for (std::size_t i = 0; i < a.automata.size(); ++i) {
    EXPECT_EQ(a.automata[i].corner, b.automata[i].corner);
    EXPECT_EQ(a.automata[i].blend, b.automata[i].blend);
    EXPECT_EQ(a.automata[i].to->lattice.density, b.automata[i].to->lattice.density);
  }
}

// A typed edit refused for what it was given changes nothing: not the hash, not the edits
// counted, not one bit of what a render sees.
TEST(World, RefusedEditsChangeNothing) {
  World world = makeWorld();
  ASSERT_EQ(world.advance(12.5), "");
  Target boat;
  boat.name = "boat";
  ASSERT_EQ(world.addTarget(boat, false, 1), "");
  const std::uint64_t hash = world.hash(), edits = world.edits();
  const Scene before = world.scene();
  WeatherLayer stratus = typicalWeatherLayer(CloudType::kStratus, 0.6);
  stratus.coverage = 1.5;
  EXPECT_THAT(world.setWeather({2, std::nullopt}, stratus), ::testing::HasSubstr("coverage"));
  stratus.coverage = 0.6;
  stratus.wind = glm::dvec2(190.0, 190.0);  // each part in range, the speed not
  EXPECT_THAT(world.setWeather({2, std::nullopt}, stratus),
              ::testing::HasSubstr("speed of at most 200 m/s"));
  EXPECT_THAT(world.setWind({{{0.0, {1.0, 0.0}}, {0.0, {2.0, 0.0}}}}),
              ::testing::HasSubstr("altitudes must increase"));
  EXPECT_THAT(world.setWind({{{0.0, {300.0, 0.0}}}}), ::testing::HasSubstr("speed"));
  Sea sea;
  sea.clarity = 2.0;
  EXPECT_THAT(world.setSea(sea), ::testing::HasSubstr("clarity"));
  EXPECT_THAT(world.setSite({95.0, 0.0, 0.0}), ::testing::HasSubstr("latitude"));
  EXPECT_THAT(world.addCloud(world.base().clouds[0]), ::testing::HasSubstr("is taken"));
  EXPECT_THAT(world.changeCloud("none", {}), ::testing::HasSubstr("no cloud is called"));
  EXPECT_THAT(world.removeCloud("none"), ::testing::HasSubstr("no cloud is called"));
  EXPECT_THAT(world.addTarget(boat, false, 2), ::testing::HasSubstr("is taken"));
  boat.name = "raft";
  EXPECT_THAT(world.addTarget(boat, false, 1), ::testing::HasSubstr("holds 1 targets"));
  EXPECT_THAT(world.moveTarget("raft", {}), ::testing::HasSubstr("no target is called"));
  EXPECT_THAT(world.removeTarget("raft"), ::testing::HasSubstr("no target is called"));
  EXPECT_EQ(world.hash(), hash);
  EXPECT_EQ(world.edits(), edits);
  expectSameScene(world.scene(), before);
  // An edit that succeeds survives a snapshot round trip.
  EllipsoidCloud copy_of_first = world.base().clouds[0];
  copy_of_first.name = "copy";
  ASSERT_EQ(world.addCloud(copy_of_first), "");
  World copy = makeWorld();
  ASSERT_EQ(copy.restore(world.snapshot()), "");
  EXPECT_EQ(copy.hash(), world.hash());
  EXPECT_EQ(copy.scene().clouds.size(), 2u);
}

// Moves the drift of `t` seconds into (t > 0) or out of (t < 0) a base scene, as edits have
// always done it.
void foldDrift(Scene& scene, const WindProfile& wind, double t) {
  for (CloudLayer& layer : scene.layers)
    layer.texture.drift_offset_m += layer.texture.drift_velocity * t;
  if (wind.empty()) return;
  for (CloudField& field : scene.fields) field.drift_m += wind.at(fieldAltitude(field)) * t;
  for (EllipsoidCloud& cloud : scene.clouds) {
    const glm::dvec3 drift(wind.at(cloudAltitude(cloud)) * t, 0.0);
    for (Ellipsoid& e : cloud.ellipsoids) e.centre += drift;
    cloud.drift_m += drift;
  }
}

// Moves everything `scene` holds by -shift, as set_site's re-centring has always moved it.
void moveContent(Scene& scene, glm::dvec2 shift) {
  const glm::dvec3 by(shift, 0.0);
  scene.camera.position -= by;
  for (CloudLayer& layer : scene.layers) layer.texture.drift_offset_m -= shift;
  for (CloudField& field : scene.fields) field.drift_m -= shift;
  for (EllipsoidCloud& cloud : scene.clouds) {
    for (Ellipsoid& e : cloud.ellipsoids) e.centre -= by;
    cloud.drift_m -= by;
  }
  for (Target& target : scene.targets) target.centre -= by;
  for (RainShaft& shaft : scene.rain_shafts) shaft.centre -= shift;
  for (auto& [key, weather] : scene.weather)
    if (!weather.region.everywhere()) weather.region.centre -= shift;
  if (scene.sea) scene.sea->origin_m -= shift;
  scene.content_origin += shift;
}

// `world` changed as edits changed it before they were typed: the whole world copied with the
// drift so far folded in, changed, the drift folded out with the new wind, and a world built
// anew from that at the same time. A world without automata, whose states a new world would
// have to simulate again.
World copyEdited(const World& world,
                 const std::function<void(Scene& now, WorldDynamics& dynamics)>& change) {
  Scene now = world.base();
  WorldDynamics dynamics = world.dynamics();
  const double t = world.timeSeconds();
  foldDrift(now, dynamics.wind, t);
  change(now, dynamics);
  if (!dynamics.wind.empty())
    for (CloudLayer& layer : now.layers)
      layer.texture.drift_velocity = dynamics.wind.at(layer.altitude_m);
  const auto& old = world.dynamics().wind.samples;
  const bool wind_changed =
      !std::equal(old.begin(), old.end(), dynamics.wind.samples.begin(),
                  dynamics.wind.samples.end(), [](const WindSample& a, const WindSample& b) {
                    return a.altitude_m == b.altitude_m && a.velocity == b.velocity;
                  });
  if (now.sea && !dynamics.wind.empty() && wind_changed) now.sea->wind = dynamics.wind.at(0.0);
  foldDrift(now, dynamics.wind, -t);
  World edited(now, dynamics);
  EXPECT_EQ(edited.advance(t), "");
  EXPECT_EQ(edited.timeNs(), world.timeNs());
  return edited;
}

// Typed edits change base_ and the state now in place; the world they leave is bit for bit the
// one a whole copy of the world, changed and built anew, would be.
TEST(World, TypedEditsEqualTheCopyEditBitForBit) {
  auto [scene, dynamics] = smallWorld();
  dynamics.automata.clear();
  scene.clouds[0].name = "first";
  World world(scene, dynamics);
  int checks = 0;
  const auto check = [&](const std::string& error, const World& expected) {
    SCOPED_TRACE(::testing::Message() << "edit " << ++checks);
    ASSERT_EQ(error, "");
    EXPECT_EQ(world.hash(), expected.hash());
    expectSameScene(world.scene(), expected.scene());
  };
  ASSERT_EQ(world.advance(37.3), "");
  Fog fog;
  fog.top_m = 80.0;
  World expected = copyEdited(world, [&](Scene& now, WorldDynamics&) { now.fog = fog; });
  check(world.setFog(fog), expected);
  ASSERT_EQ(world.advance(0.7), "");
  Target boat;
  boat.name = "boat";
  boat.centre = {1.0, 2.0, 3.0};
  expected = copyEdited(world, [&](Scene& now, WorldDynamics&) { now.targets.push_back(boat); });
  check(world.addTarget(boat, false, 4), expected);
  expected = copyEdited(world, [&](Scene& now, WorldDynamics&) {
    now.targets[0].centre = {5.0, 6.0, 7.0};
    now.targets[0].orientation.heading_deg = 45.0;
  });
  check(world.moveTarget("boat", {glm::dvec3(5.0, 6.0, 7.0), 45.0, {}, {}}), expected);
  ASSERT_EQ(world.advance(2.5), "");
  EllipsoidCloud extra = world.base().clouds[0];
  extra.name = "extra";
  expected = copyEdited(world, [&](Scene& now, WorldDynamics& d) {
    now.clouds.push_back(extra);
    d.clouds.emplace_back();
  });
  check(world.addCloud(extra), expected);
  const glm::dvec3 move(10.0, -3.0, 400.0);  // up into another wind
  expected = copyEdited(world, [&](Scene& now, WorldDynamics&) {
    for (Ellipsoid& e : now.clouds[1].ellipsoids) e.centre += move;
    now.clouds[1].drift_m += move;
    now.clouds[1].threshold_centre = 0.2;
  });
  check(world.changeCloud("extra", {move, 0.2, {}, {}, {}}), expected);
  ASSERT_EQ(world.advance(4.0), "");
  WeatherLayer cumulus = typicalWeatherLayer(CloudType::kCumulus, 0.3);
  cumulus.wind = glm::dvec2(3.0, 4.0);
  const WeatherKey key{1, std::nullopt};
  expected = copyEdited(world, [&](Scene& now, WorldDynamics& d) {
    EXPECT_EQ(placeWeather(now, d, key, cumulus), "");
  });
  check(world.setWeather(key, cumulus), expected);
  Sea sea;
  expected = copyEdited(world, [&](Scene& now, WorldDynamics&) {
    now.sea = sea;
    now.sea->origin_m = -now.content_origin;  // setSea lays a new sea's waves out so
  });
  check(world.setSea(sea), expected);
  Haze haze;
  haze.visibility_m = 9000.0;
  expected = copyEdited(world, [&](Scene& now, WorldDynamics&) { now.haze = haze; });
  check(world.setHaze(haze), expected);
  ASSERT_EQ(world.advance(1.5), "");
  // The first site places the world; the next re-centres it, moving all it holds.
  const Site alps{45.0, 7.0, 0.0}, east{45.0, 7.5, 0.0};
  expected = copyEdited(world, [&](Scene& now, WorldDynamics&) { now.site = alps; });
  check(world.setSite(alps), expected);
  ASSERT_EQ(world.advance(3.0), "");
  const glm::dvec2 shift = recentred(alps, east.latitude_deg, east.longitude_deg).shift;
  ASSERT_GT(glm::length(shift), 30000.0);
  expected = copyEdited(world, [&](Scene& now, WorldDynamics&) {
    now.site = east;
    moveContent(now, shift);
  });
  check(world.setSite(east), expected);
  ASSERT_EQ(world.advance(0.5), "");
  expected = copyEdited(world, [&](Scene& now, WorldDynamics&) {
    now.clouds[1].colour = {1, 0, 0};
  });
  check(world.changeCloud("extra", {{}, {}, {}, {}, glm::dvec3(1.0, 0.0, 0.0)}), expected);
  ASSERT_EQ(world.advance(9.0), "");
  const WindProfile calm{{{0.0, {-20.0, 5.0}}, {2000.0, {4.0, 1.0}}}};
  expected = copyEdited(world, [&](Scene&, WorldDynamics& d) { d.wind = calm; });
  check(world.setWind(calm), expected);
  ASSERT_EQ(world.advance(2.0), "");
  expected = copyEdited(world, [&](Scene&, WorldDynamics& d) { d.wind = {}; });
  check(world.setWind({}), expected);  // no wind: what drifted stays where it is
  ASSERT_EQ(world.advance(2.0), "");
  expected = copyEdited(world, [&](Scene&, WorldDynamics& d) { d.wind = calm; });
  check(world.setWind(calm), expected);
  ASSERT_EQ(world.advance(1.0), "");
  expected = copyEdited(
      world, [&](Scene& now, WorldDynamics& d) { EXPECT_EQ(placeWeather(now, d, key, {}), ""); });
  check(world.setWeather(key, {}), expected);
  expected = copyEdited(world, [&](Scene& now, WorldDynamics& d) {
    now.clouds.erase(now.clouds.begin());
    d.clouds.erase(d.clouds.begin());
  });
  check(world.removeCloud("first"), expected);
  expected = copyEdited(world, [&](Scene& now, WorldDynamics&) { now.targets.clear(); });
  check(world.removeTarget("boat"), expected);
  ASSERT_EQ(world.advance(5.0), "");
  World restored = makeWorld();
  ASSERT_EQ(restored.restore(world.snapshot()), "");
  check("", restored);
}

// The state now is brought up to date when read: advancing many times and reading once hands
// out the same scene, bit for bit, as reading after every advance, edits between or not, and
// as a world restored from a snapshot (which builds it anew).
TEST(World, ManyAdvancesThenOneReadEqualReadingEachTime) {
  World once = makeWorld(), each = makeWorld();
  Target boat;
  boat.name = "boat";
  for (World* w : {&once, &each}) ASSERT_EQ(w->addTarget(boat, false, 1), "");
  const WeatherLayer cumulus = typicalWeatherLayer(CloudType::kCumulus, 0.3);
  const auto step = [&](int i) {
    for (World* w : {&once, &each}) {
      std::string error = w->advance(0.1 + 0.01 * (i % 7));
      if (i % 10 == 3) error += w->moveTarget("boat", {glm::dvec3(i, 0.0, 0.0), {}, {}, {}});
      if (i == 25) error += w->setWeather({1, std::nullopt}, cumulus);
      if (i == 31) error += w->setFog(Fog{});
      if (i == 37) error += w->setSite({45.0, 7.0, 0.0});
      ASSERT_EQ(error, "");
    }
    static_cast<void>(each.scene());
  };
  for (int i = 0; i < 60; ++i) step(i);
  EXPECT_EQ(once.hash(), each.hash());
  {
    SCOPED_TRACE("read once against read each time");
    expectSameScene(once.scene(), each.scene());
  }
  World restored = makeWorld();
  ASSERT_EQ(restored.restore(once.snapshot()), "");
  expectSameScene(restored.scene(), once.scene());
  // The sun's light reaches the automata's views on the next read, too.
  Sun sun = once.base().sun;
  sun.elevation_deg = 15.0;
  for (World* w : {&once, &each}) w->setSun(sun);
  EXPECT_EQ(once.scene().automata[0].to->lattice.sunlight,
            each.scene().automata[0].to->lattice.sunlight);
  EXPECT_NE(once.scene().automata[0].to->lattice.sunlight,
            restored.scene().automata[0].to->lattice.sunlight);
}

// A view of the world from a camera (the daemon's views) is the state now with only its camera
// set: no copy, no change to the hash, and what time sets is as scene() has it.
TEST(World, SeenFromSetsTheCameraAloneAndKeepsTheHash) {
  World world = makeWorld(), plain = makeWorld();
  for (World* w : {&world, &plain}) ASSERT_EQ(w->advance(12.5), "");
  const std::uint64_t hash = world.hash();
  Camera camera = world.base().camera;
  camera.position += glm::dvec3(1234.0, -50.0, 300.0);
  camera.orientation.heading_deg = 77.0;
  camera.width = 321;
  const Scene& seen = world.seenFrom(camera);
  EXPECT_EQ(&seen, &world.scene());  // the world's own state, not a copy
  EXPECT_EQ(seen.camera.position, camera.position);
  EXPECT_EQ(seen.camera.orientation.heading_deg, 77.0);
  EXPECT_EQ(seen.camera.width, 321);
  EXPECT_EQ(world.hash(), hash);
  EXPECT_EQ(world.hash(), plain.hash());
  Scene expected = plain.scene();
  expected.camera = camera;
  expectSameScene(seen, expected);
}

TEST(World, HashesDifferWhenTheWorldDiffers) {
  World a = makeWorld(), b = makeWorld();
  EXPECT_EQ(a.hash(), b.hash());
  ASSERT_EQ(b.advance(1e-9), "");
  EXPECT_NE(a.hash(), b.hash());
}

// The weather is held once, in the world: a layer set as it already is changes nothing (a CIGI
// host repeats its packets every frame), a new one replaces exactly what the old one made, a
// region's layer is its own, and the weather as set survives a snapshot.
TEST(World, WeatherLayersAreHeldOnceAndReplacedWhole) {
  World world = makeWorld();
  auto named = [&](const std::string& prefix) {
    const Scene s = world.scene();
    int n = 0;
    for (const CloudLayer& l : s.layers) n += l.name.rfind(prefix, 0) == 0;
    for (const CloudField& f : s.fields) n += f.name.rfind(prefix, 0) == 0;
    return n;
  };
  const std::size_t user_layers = world.scene().layers.size();
  WeatherLayer stratus = typicalWeatherLayer(CloudType::kStratus, 0.6);
  bool changed = false;
  ASSERT_EQ(world.setWeather({1, std::nullopt}, stratus, &changed), "");
  EXPECT_TRUE(changed);
  ASSERT_EQ(world.base().weather.size(), 1u);
  EXPECT_EQ(world.base().weather.at({1, std::nullopt}), stratus);
  const int stratus_items = named("weather/1");
  EXPECT_GT(stratus_items, 0);
  const std::uint64_t hash = world.hash();
  ASSERT_EQ(world.setWeather({1, std::nullopt}, stratus, &changed), "");
  EXPECT_FALSE(changed);
  EXPECT_EQ(world.hash(), hash);

  // Another genus in the same layer replaces the stratus's planes, and nothing else.
  const WeatherLayer cumulus = typicalWeatherLayer(CloudType::kCumulus, 0.3);
  ASSERT_EQ(world.setWeather({1, std::nullopt}, cumulus, &changed), "");
  EXPECT_TRUE(changed);
  EXPECT_EQ(world.scene().fields.size(), 1u);
  EXPECT_EQ(world.scene().layers.size() - user_layers, std::size_t(named("weather/1")) - 1);
  // A region's layer 1 is a layer of its own.
  WeatherLayer regional = stratus;
  regional.region.half_size = {5000.0, 5000.0};
  ASSERT_EQ(world.setWeather({1, std::uint16_t(7)}, regional, &changed), "");
  EXPECT_EQ(named("weather/region7/1"), stratus_items);
  EXPECT_EQ(world.scene().fields.size(), 1u);

  // Invalid: refused, nothing changes.
  WeatherLayer bad = stratus;
  bad.coverage = 1.5;
  const std::uint64_t before = world.hash();
  EXPECT_THAT(world.setWeather({2, std::nullopt}, bad, &changed), ::testing::HasSubstr("coverage"));
  EXPECT_FALSE(changed);
  EXPECT_EQ(world.hash(), before);

  // The weather as set comes back from a snapshot with its clouds.
  World copy = makeWorld();
  ASSERT_EQ(copy.restore(world.snapshot()), "");
  EXPECT_EQ(copy.base().weather, world.base().weather);
  EXPECT_EQ(copy.hash(), world.hash());

  // Type none removes the layer and all it made; the user's own layers stay.
  ASSERT_EQ(world.setWeather({1, std::nullopt}, {}, &changed), "");
  EXPECT_TRUE(changed);
  EXPECT_EQ(named("weather/1"), 0);
  EXPECT_EQ(world.scene().fields.size(), 0u);
  EXPECT_EQ(world.base().weather.count({1, std::nullopt}), 0u);
  EXPECT_EQ(world.base().weather.size(), 1u);  // the region's
  ASSERT_EQ(world.setWeather({1, std::nullopt}, {}, &changed), "");
  EXPECT_FALSE(changed);
}

// Clouds keep their development beside them: removing one takes its schedules with it and
// leaves the others' schedules on the clouds they belong to. Names are unique; what is not
// found is named.
TEST(World, CloudsAndTargetsAreEditedByNameWithTheirDevelopment) {
  auto [scene, d] = smallWorld();
  scene.clouds[0].name = "first";
  EllipsoidCloud second = scene.clouds[0];
  second.name = "second";
  scene.clouds.push_back(second);
  d.clouds.push_back({});
  d.clouds[1].threshold_centre = {{0.0, 100.0}, {0.2, 0.7}};  // the second's own schedule
  World world(scene, d);
  EXPECT_THAT(world.addCloud(second), ::testing::HasSubstr("is taken"));
  ASSERT_EQ(world.removeCloud("first"), "");
  ASSERT_EQ(world.dynamics().clouds.size(), 1u);
  EXPECT_EQ(world.dynamics().clouds[0].threshold_centre.values, (std::vector<double>{0.2, 0.7}));
  EXPECT_EQ(world.scene().clouds[0].name, "second");
  EXPECT_THAT(world.removeCloud("first"), ::testing::HasSubstr("no cloud is called"));
  ASSERT_EQ(world.changeCloud("second", {glm::dvec3(10.0, 0.0, 0.0), std::nullopt, std::nullopt,
                                         std::nullopt, std::nullopt}),
            "");
  EXPECT_DOUBLE_EQ(world.base().clouds[0].drift_m.x, 10.0);
  EXPECT_THAT(world.changeCloud("third", {}), ::testing::HasSubstr("no cloud is called"));
  second.name = "third";
  ASSERT_EQ(world.addCloud(second), "");
  EXPECT_EQ(world.dynamics().clouds.size(), 2u);  // the new cloud develops not at all

  Target t;
  t.name = "boat";
  ASSERT_EQ(world.addTarget(t, false, 1), "");
  EXPECT_THAT(world.addTarget(t, false, 1), ::testing::HasSubstr("is taken"));
  t.centre = {5.0, 6.0, 7.0};
  ASSERT_EQ(world.addTarget(t, true, 1), "");  // replaced, not counted again
  EXPECT_EQ(world.base().targets.at(0).centre, t.centre);
  t.name = "raft";
  EXPECT_THAT(world.addTarget(t, false, 1), ::testing::HasSubstr("holds 1 targets"));
  ASSERT_EQ(world.moveTarget("boat", {std::nullopt, 90.0, std::nullopt, std::nullopt}), "");
  EXPECT_EQ(world.base().targets[0].orientation.heading_deg, 90.0);
  EXPECT_EQ(world.base().targets[0].centre, glm::dvec3(5.0, 6.0, 7.0));
  EXPECT_THAT(world.moveTarget("raft", {}), ::testing::HasSubstr("no target is called"));
  ASSERT_EQ(world.removeTarget("boat"), "");
  EXPECT_TRUE(world.base().targets.empty());
}

// Fog and haze set as they are change nothing; set otherwise, they change the world.
TEST(World, FogAndHazeSetAgainChangeNothing) {
  World world = makeWorld();
  bool changed = false;
  Fog fog;
  fog.top_m = 80.0;
  ASSERT_EQ(world.setFog(fog, &changed), "");
  EXPECT_TRUE(changed);
  const std::uint64_t hash = world.hash();
  ASSERT_EQ(world.setFog(fog, &changed), "");
  EXPECT_FALSE(changed);
  ASSERT_EQ(world.setHaze(std::nullopt, &changed), "");
  EXPECT_FALSE(changed);
  EXPECT_EQ(world.hash(), hash);
  ASSERT_EQ(world.setHaze(Haze{}, &changed), "");
  EXPECT_TRUE(changed);
  EXPECT_NE(world.hash(), hash);
}

// The sea (world/sea.h): held once, refused whole when invalid, following the surface wind,
// and kept by snapshots.
TEST(World, TheSeaFollowsTheSurfaceWindAndSnapshotsKeepIt) {
  World world = makeWorld();
  ASSERT_EQ(world.advance(3.0), "");
  Sea sea;
  sea.wind = {2.0, 0.0};  // the world's wind at altitude 0
  sea.fetch_m = 30000.0;
  sea.trains.push_back({});
  sea.trains[0].id = 7;
  sea.trains[0].direction_deg = 45.0;
  bool changed = false;
  ASSERT_EQ(world.setSea(sea, &changed), "");
  EXPECT_TRUE(changed);
  EXPECT_EQ(world.scene().sea, sea);  // what a render sees
  const std::uint64_t hash = world.hash();
  ASSERT_EQ(world.setSea(sea, &changed), "");
  EXPECT_FALSE(changed);
  EXPECT_EQ(world.hash(), hash);

  // An invalid sea is refused and changes nothing.
  const auto refused = [&](Sea bad, const std::string& words) {
    const std::string error = world.setSea(bad, &changed);
    EXPECT_THAT(error, ::testing::HasSubstr(words));
    EXPECT_FALSE(changed);
    EXPECT_EQ(world.hash(), hash);
  };
  Sea bad = sea;
  bad.clarity = 1.5;
  refused(bad, "clarity: 1.5 is out of range (allowed: 0 to 1)");
  bad = sea;
  bad.temperature_c = std::nan("");
  refused(bad, "temperature");
  bad = sea;
  bad.trains.push_back(sea.trains[0]);
  refused(bad, "wave: id 7 is given twice");
  bad = sea;
  bad.trains[0].wavelength_m = 0.0;
  refused(bad, "wave 7 wavelength: 0 is out of range (allowed: 1 to 2000)");
  bad = sea;
  bad.trains.assign(kMaxWaveTrains + 1, WaveTrain{});
  for (int i = 0; i <= kMaxWaveTrains; ++i) bad.trains[std::size_t(i)].id = i;
  refused(bad, "9 wave trains (allowed: at most 8)");
  bad = sea;
  bad.wind = {150.0, 150.0};
  refused(bad, "wind");

  // The wind at altitude 0 is the sea's, whatever changes it; an edit that leaves the wind alone
  // leaves the sea alone.
  ASSERT_EQ(world.setWind({{{0.0, {-6.0, 8.0}}}}), "");
  EXPECT_EQ(world.base().sea->wind, glm::dvec2(-6.0, 8.0));
  ASSERT_EQ(world.setWind({{{2000.0, {1.0, 1.0}}}}), "");
  EXPECT_EQ(world.base().sea->wind, glm::dvec2(1.0, 1.0));  // held below the lowest sample
  ASSERT_EQ(world.setWeather({1, std::nullopt},
                             [] {
                               WeatherLayer w;
                               w.type = CloudType::kStratus;
                               w.base_m = 800.0;
                               w.thickness_m = 300.0;
                               w.wind = glm::dvec2(3.0, 4.0);
                               return w;
                             }()),
            "");
  EXPECT_EQ(world.base().sea->wind, glm::dvec2(3.0, 4.0));  // a layer's wind, now the lowest
  ASSERT_EQ(world.setFog(Fog{}), "");
  EXPECT_EQ(world.base().sea->wind, glm::dvec2(3.0, 4.0));

  // Snapshots keep the sea bit for bit; a snapshot's sea out of range is refused.
  World copy = makeWorld();
  ASSERT_EQ(copy.restore(world.snapshot()), "");
  EXPECT_EQ(copy.base().sea, world.base().sea);
  EXPECT_EQ(copy.hash(), world.hash());
  ASSERT_EQ(world.setSea(std::nullopt, &changed), "");
  EXPECT_TRUE(changed);
  EXPECT_FALSE(world.scene().sea.has_value());
  ASSERT_EQ(copy.restore(world.snapshot()), "");
  EXPECT_FALSE(copy.base().sea.has_value());
}

}  // namespace
}  // namespace nephele
