#include "protocol/messages.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "protocol/cloud_codes.h"

namespace nephele {
namespace {

using ::testing::HasSubstr;

Request parsed(std::string_view line) {
  auto r = parseRequest(line);
  EXPECT_TRUE(std::holds_alternative<Request>(r))
      << (std::holds_alternative<BadRequest>(r) ? std::get<BadRequest>(r).error.message : "");
  return std::holds_alternative<Request>(r) ? std::get<Request>(r) : Request{};
}

BadRequest rejected(std::string_view line) {
  auto r = parseRequest(line);
  EXPECT_TRUE(std::holds_alternative<BadRequest>(r)) << line;
  return std::holds_alternative<BadRequest>(r) ? std::get<BadRequest>(r) : BadRequest{};
}

TEST(Messages, ParsesEveryCommandWithItsFields) {
  const Request view = parsed(
      R"({"id":7,"cmd":"set_view","view":"front","position":[1,2,3],"heading":-90,"width":320,)"
      R"("format":"png","channels":["coverage"]})");
  EXPECT_EQ(view.id, 7);
  const auto& v = std::get<command::SetView>(view.command);
  EXPECT_EQ(v.view, "front");
  EXPECT_EQ(*v.patch.position, glm::dvec3(1, 2, 3));
  EXPECT_EQ(*v.patch.heading, -90.0);
  EXPECT_EQ(*v.patch.width, 320);
  EXPECT_FALSE(v.patch.pitch.has_value());
  EXPECT_EQ(v.patch.image->format, ImageFormat::kPng);
  EXPECT_FALSE(v.patch.image->colour);
  EXPECT_TRUE(v.patch.image->coverage);

  const auto w = std::get<command::SetWeather>(
      parsed(R"({"cmd":"set_weather","layer":2,"type":9,"base":1200,"thickness":400,)"
             R"("coverage":75,"wind":[3,-4]})")
          .command);
  EXPECT_EQ(w.layer, 2);
  EXPECT_EQ(w.weather.type, CloudType::kStratocumulus);
  EXPECT_EQ(w.weather.base_m, 1200.0);
  EXPECT_EQ(w.weather.coverage, 0.75);
  EXPECT_EQ(*w.weather.wind, glm::dvec2(3, -4));
  EXPECT_TRUE(w.weather.region.everywhere());
  // One message covers a 300 km macrocluster on one side of a front.
  const auto m = std::get<command::SetWeather>(
      parsed(R"({"cmd":"set_weather","layer":1,"type":7,"coverage":40,"centre":[1e4,-2e4],)"
             R"("size":[3e5,2e5],"heading":45,"edge":1e4,"front":"right","transition":2e4,)"
             R"("spacing":25000,"variation":0.6})")
          .command);
  EXPECT_EQ(m.weather.region.half_size, glm::dvec2(1.5e5, 1e5));
  EXPECT_EQ(m.weather.region.centre, glm::dvec2(1e4, -2e4));
  EXPECT_EQ(m.weather.region.side, 1);
  EXPECT_EQ(m.weather.region.transition_m, 2e4);
  EXPECT_EQ(m.weather.clusters.amount, 0.6);

  EXPECT_EQ(std::get<command::Tick>(parsed(R"({"cmd":"tick","dt":0.02})").command).dt, 0.02);
  EXPECT_EQ(
      std::get<command::Subscribe>(parsed(R"({"cmd":"subscribe","view":"a","rate":5})").command)
          .rate_hz,
      5.0);
  // Issue 16: several views from one tick, a camera for one render, atmosphere, targets.
  const auto r = std::get<command::Render>(
      parsed(R"({"cmd":"render","views":["a","b"],"format":"raw"})").command);
  EXPECT_EQ(r.views, (std::vector<std::string>{"a", "b"}));
  const auto rc = std::get<command::Render>(
      parsed(R"({"cmd":"render","view":"a","camera":{"position":[1,2,3],"vfov":30,"width":8}})")
          .command);
  EXPECT_EQ(*rc.camera->position, glm::dvec3(1, 2, 3));
  EXPECT_EQ(*rc.camera->width, 8);
  EXPECT_FALSE(rc.camera->image.has_value());
  const auto fog = std::get<command::SetFog>(
      parsed(R"({"cmd":"set_fog","top":200,"visibility":500,"colour":[0.5,0.5,0.6]})").command);
  EXPECT_EQ(*fog.top, 200.0);
  EXPECT_EQ(*fog.visibility, 500.0);
  EXPECT_FALSE(fog.enabled.has_value());
  const auto sun = std::get<command::SetSun>(
      parsed(R"({"cmd":"set_sun","utc":"2026-03-20T14:00+02:00"})").command);
  EXPECT_EQ(sun.utc->hour, 12);
  EXPECT_EQ(
      *std::get<command::SetTime>(parsed(R"({"cmd":"set_time","mode":"lockstep"})").command).mode,
      TickMode::kLockstep);
  const auto move = std::get<command::MoveTarget>(
      parsed(R"({"cmd":"move_target","name":"t","centre":[1,2,3],"roll":5})").command);
  EXPECT_EQ(*move.centre, glm::dvec3(1, 2, 3));
  EXPECT_EQ(*move.roll, 5.0);
  EXPECT_EQ(commandName(parsed(R"({"cmd":"list_targets"})").command), "list_targets");
  EXPECT_EQ(parsed(R"({"id":"abc","cmd":"hash"})").id, "abc");
  EXPECT_EQ(commandName(parsed(R"({"cmd":"stats"})").command), "stats");
}

// The host codes of the genera (protocol/cloud_codes.h) are CIGI 3.3's Weather Control cloud
// types, written out here from the ICD; every genus of the world's table has one, and the
// socket protocol's set_weather reads them.
TEST(CloudCodes, AreCigisAndEveryGenusHasOne) {
  const char* icd[] = {"none",         "altocumulus",   "altostratus",  "cirrocumulus",
                       "cirrostratus", "cirrus",        "cumulonimbus", "cumulus",
                       "nimbostratus", "stratocumulus", "stratus"};
  ASSERT_EQ(std::size(icd), std::size_t(kCloudTypeCodes));
  for (int code = 0; code < kCloudTypeCodes; ++code) {
    const std::optional<CloudType> type = cloudTypeFromCode(code);
    ASSERT_TRUE(type.has_value()) << code;
    EXPECT_EQ(cloudTypeName(*type), icd[code]);
    EXPECT_EQ(cloudTypeCode(*type), code);
    const Request r =
        parsed(R"({"cmd":"set_weather","layer":1,"type":)" + std::to_string(code) + "}");
    EXPECT_EQ(std::get<command::SetWeather>(r.command).weather.type, *type);
  }
  for (int i = 0; i < kCloudTypeCount; ++i)
    EXPECT_EQ(cloudTypeFromCode(cloudTypeCode(CloudType(i))), CloudType(i)) << i;
  EXPECT_FALSE(cloudTypeFromCode(-1).has_value());
  EXPECT_FALSE(cloudTypeFromCode(kCloudTypeCodes).has_value());
  EXPECT_THAT(rejected(R"({"cmd":"set_weather","layer":1,"type":11})").error.message,
              HasSubstr("type"));
  // A layer without a type names every code with its genus, from the one code table.
  EXPECT_THAT(rejected(R"({"cmd":"set_weather","layer":1})").error.message,
              HasSubstr("allowed: 0 to 10, CIGI cloud types: 0 none, 1 altocumulus, 2 "
                        "altostratus, 3 cirrocumulus, 4 cirrostratus, 5 cirrus, 6 cumulonimbus, "
                        "7 cumulus, 8 nimbostratus, 9 stratocumulus, 10 stratus)"));
}

// Precipitation (MODEL.md section 17): on a cloud layer, and CIGI's precipitation layers 4 to 9,
// whose kind is the layer's.
TEST(Messages, SetWeatherCarriesPrecipitation) {
  const auto rain = std::get<command::SetWeather>(
      parsed(R"({"cmd":"set_weather","layer":1,"type":8,"base":900,"precipitation":"rain",)"
             R"("precipitation_rate":4})")
          .command);
  EXPECT_EQ(rain.weather.precipitation.kind, PrecipitationKind::kRain);
  EXPECT_EQ(rain.weather.precipitation.rate_mm_h, 4.0);
  const auto snow = std::get<command::SetWeather>(
      parsed(R"({"cmd":"set_weather","layer":5,"type":0,"base":0,"thickness":800,)"
             R"("precipitation_rate":2})")
          .command);
  EXPECT_EQ(snow.layer, 5);
  EXPECT_EQ(snow.weather.precipitation.kind, PrecipitationKind::kSnow);
  const auto off = std::get<command::SetWeather>(
      parsed(R"({"cmd":"set_weather","layer":5,"type":0,"precipitation":"none"})").command);
  EXPECT_EQ(off.weather.precipitation.kind, PrecipitationKind::kNone);
  EXPECT_THAT(rejected(R"({"cmd":"set_weather","layer":4,"type":7})").error.message,
              HasSubstr("precipitation only"));
  EXPECT_THAT(
      rejected(R"({"cmd":"set_weather","layer":4,"type":0,"precipitation":"snow"})").error.message,
      HasSubstr("holds rain"));
  EXPECT_THAT(rejected(R"({"cmd":"set_weather","layer":1,"type":8,"precipitation":"drizzle"})")
                  .error.message,
              HasSubstr("allowed: none, rain"));
  EXPECT_THAT(rejected(R"({"cmd":"set_weather","layer":4,"type":0,"precipitation_rate":501})")
                  .error.message,
              HasSubstr("precipitation_rate"));
  EXPECT_THAT(rejected(R"({"cmd":"set_weather","layer":10,"type":0})").error.message,
              HasSubstr("layer"));
}

// set_site: a latitude and longitude together, a grid north only with them.
TEST(Messages, SetSiteTakesAPlaceOnTheEarth) {
  const auto site = std::get<command::SetSite>(
      parsed(R"({"cmd":"set_site","latitude":60.5,"longitude":-179.5,"grid":12})").command);
  EXPECT_EQ(site.latitude, 60.5);
  EXPECT_EQ(site.longitude, -179.5);
  EXPECT_EQ(site.grid, 12.0);
  EXPECT_FALSE(std::get<command::SetSite>(parsed(R"({"cmd":"set_site"})").command).latitude);
  const std::pair<const char*, const char*> errors[] = {
      {R"({"cmd":"set_site","latitude":91,"longitude":0})",
       "latitude: 91 is out of range (allowed: -90 to 90)"},
      {R"({"cmd":"set_site","latitude":0,"longitude":181})",
       "longitude: 181 is out of range (allowed: -180 to 180)"},
      {R"({"cmd":"set_site","latitude":10})", "longitude: is missing"},
      {R"({"cmd":"set_site","grid":1})", "grid: needs latitude and longitude"},
      {R"({"cmd":"set_site","latitude":0,"longitude":0,"height":1})", "height: unknown field"},
  };
  for (const auto& [request, error] : errors)
    EXPECT_THAT(rejected(request).error.message, HasSubstr(error)) << request;
}

// set_sea: the sea's fields and wave trains by id, each range from world/limits.h.
TEST(Messages, SetSeaCarriesTheSeaAndItsWaveTrains) {
  const auto sea = std::get<command::SetSea>(
      parsed(R"({"cmd":"set_sea","fetch":2e4,"temperature":-2,"clarity":1,"whitecaps":false,)"
             R"("seed":9007199254740993,"waves":[{"id":255,"height":30,"wavelength":1,)"
             R"("period":0,"direction":-360,"phase":360},{"id":0,"enabled":false}]})")
          .command);
  EXPECT_FALSE(sea.enabled.has_value());
  EXPECT_EQ(*sea.fetch, 2e4);
  EXPECT_EQ(*sea.temperature, -2.0);
  EXPECT_EQ(*sea.clarity, 1.0);
  EXPECT_EQ(*sea.whitecaps, false);
  EXPECT_EQ(*sea.seed, 9007199254740993ull);  // a seed is an integer, held exactly
  ASSERT_EQ(sea.waves.size(), 2u);
  EXPECT_EQ(sea.waves[0].id, 255);
  EXPECT_FALSE(sea.waves[0].enabled.has_value());
  EXPECT_EQ(*sea.waves[0].height, 30.0);
  EXPECT_EQ(*sea.waves[0].wavelength, 1.0);
  EXPECT_EQ(*sea.waves[0].period, 0.0);
  EXPECT_EQ(*sea.waves[0].direction, -360.0);
  EXPECT_EQ(*sea.waves[0].phase, 360.0);
  EXPECT_EQ(sea.waves[1].id, 0);
  EXPECT_EQ(sea.waves[1].enabled, false);
  EXPECT_FALSE(sea.waves[1].height.has_value());
  // No field: the sea is read back; enabled false removes it.
  const auto bare = std::get<command::SetSea>(parsed(R"({"cmd":"set_sea"})").command);
  EXPECT_FALSE(bare.enabled || bare.fetch || bare.temperature || bare.clarity || bare.whitecaps ||
               bare.seed || !bare.waves.empty());
  EXPECT_EQ(
      std::get<command::SetSea>(parsed(R"({"cmd":"set_sea","enabled":false})").command).enabled,
      false);

  const std::pair<const char*, const char*> errors[] = {
      {R"({"cmd":"set_sea","fetch":-1})", "fetch: -1 is out of range (allowed: 0 to 2e+06)"},
      {R"({"cmd":"set_sea","temperature":41})",
       "temperature: 41 is out of range (allowed: -2 to 40)"},
      {R"({"cmd":"set_sea","clarity":1.5})", "clarity: 1.5 is out of range (allowed: 0 to 1)"},
      {R"({"cmd":"set_sea","whitecaps":1})", "whitecaps: must be true or false"},
      {R"({"cmd":"set_sea","seed":-1})", "seed: -1 is out of range"},
      {R"({"cmd":"set_sea","enabled":false,"clarity":0.5})", "false removes the sea"},
      {R"({"cmd":"set_sea","waves":{"id":1}})", "waves: must be an array of 1 to 8 objects"},
      {R"({"cmd":"set_sea","waves":[]})", "waves: must be an array of 1 to 8"},
      {R"({"cmd":"set_sea","waves":[1]})", "waves[0]: must be an object"},
      {R"({"cmd":"set_sea","waves":[{"height":1}]})",
       "waves[0].id: is missing (allowed: 0 to 255)"},
      {R"({"cmd":"set_sea","waves":[{"id":256}]})", "waves[0].id: 256 is out of range"},
      {R"({"cmd":"set_sea","waves":[{"id":1},{"id":1}]})", "waves[1]: id 1 is repeated"},
      {R"({"cmd":"set_sea","waves":[{"id":1,"height":31}]})",
       "waves[0].height: 31 is out of range (allowed: 0 to 30)"},
      {R"({"cmd":"set_sea","waves":[{"id":1,"wavelength":0.5}]})",
       "waves[0].wavelength: 0.5 is out of range (allowed: 1 to 2000)"},
      {R"({"cmd":"set_sea","waves":[{"id":1,"period":61}]})",
       "waves[0].period: 61 is out of range (allowed: 0 to 60)"},
      {R"({"cmd":"set_sea","waves":[{"id":1,"direction":400}]})",
       "waves[0].direction: 400 is out of range (allowed: -360 to 360)"},
      {R"({"cmd":"set_sea","waves":[{"id":1,"phase":-361}]})",
       "waves[0].phase: -361 is out of range (allowed: -360 to 360)"},
      {R"({"cmd":"set_sea","waves":[{"id":1,"enabled":false,"height":2}]})",
       "false removes the wave train"},
      {R"({"cmd":"set_sea","waves":[{"id":1,"leading":5}]})", "waves[0].leading: unknown field"},
      {R"({"cmd":"set_sea","wind":[1,2]})", "wind: unknown field"},
  };
  for (const auto& [line, words] : errors) {
    const BadRequest bad = rejected(line);
    EXPECT_EQ(bad.error.code, ErrorCode::kBadField) << line;
    EXPECT_THAT(bad.error.message, HasSubstr(words)) << line;
  }
  const std::string nine = [] {
    std::string waves;
    for (int i = 0; i < 9; ++i)
      waves += (i ? "," : "") + std::string(R"({"id":)") + char('0' + i) + "}";
    return R"({"cmd":"set_sea","waves":[)" + waves + "]}";
  }();
  EXPECT_THAT(rejected(nine).error.message, HasSubstr("1 to 8"));
}

TEST(Messages, DefaultChannelsFollowTheFormat) {
  auto image = [](std::string_view line) {
    return *std::get<command::Render>(parsed(line).command).image;
  };
  EXPECT_TRUE(image(R"({"cmd":"render","view":"v","format":"raw"})").coverage);
  EXPECT_TRUE(image(R"({"cmd":"render","view":"v","format":"exr"})").coverage);
  EXPECT_FALSE(image(R"({"cmd":"render","view":"v","format":"png"})").coverage);
  EXPECT_FALSE(std::get<command::Render>(parsed(R"({"cmd":"render","view":"v"})").command)
                   .image.has_value());  // the view's own
}

TEST(Messages, ErrorsNameTheFieldAndWhatIsAllowed) {
  struct Case {
    const char* line;
    ErrorCode code;
    const char* words;
  };
  const Case cases[] = {
      {"not json", ErrorCode::kBadJson, "not valid JSON"},
      {"[1]", ErrorCode::kBadJson, "object"},
      {R"({"id":3})", ErrorCode::kBadField, "cmd: is missing"},
      {R"({"cmd":"fly"})", ErrorCode::kUnknownCommand, "allowed: hello, get_view"},
      {R"({"cmd":"tick","dt":"1"})", ErrorCode::kBadField, "dt: must be a number"},
      {R"({"cmd":"tick","dt":1e9})", ErrorCode::kBadField, "allowed: 0 to 3600"},
      {R"({"cmd":"tick","dt":1,"speed":2})", ErrorCode::kBadField, "speed: unknown field"},
      {R"({"cmd":"set_time","advance":2e7})", ErrorCode::kBadField, "allowed: 0 to 1e+07"},
      {R"({"cmd":"set_view","view":"a","position":[0,0,-1]})", ErrorCode::kBadField, "z >= 0"},
      {R"({"cmd":"set_view","view":"a","position":[0,0]})", ErrorCode::kBadField, "3 numbers"},
      {R"({"cmd":"set_view","view":"","heading":1})", ErrorCode::kBadField, "view"},
      {R"({"cmd":"set_weather","type":1})", ErrorCode::kBadField, "layer: is missing"},
      {R"({"cmd":"set_weather","layer":1})", ErrorCode::kBadField, "1 altocumulus"},
      {R"({"cmd":"set_weather","layer":1,"type":3,"wind":[150,150]})", ErrorCode::kBadField,
       "200 m/s"},
      {R"({"cmd":"set_weather","layer":1,"type":7,"size":[0,1e5]})", ErrorCode::kBadField, "size"},
      {R"({"cmd":"set_weather","layer":1,"type":7,"transition":500})", ErrorCode::kBadField,
       "front left or right"},
      {R"({"cmd":"set_weather","layer":1,"type":10,"spacing":1e4,"variation":0.5})",
       ErrorCode::kBadField, "heaps only"},
      {R"({"cmd":"set_weather","layer":1,"type":7,"front":"north"})", ErrorCode::kBadField,
       "none, left, right"},
      {R"({"cmd":"render","view":"a","channels":["colour","colour"]})", ErrorCode::kBadField,
       "repeated"},
      {R"({"cmd":"render","view":"a","format":"jpeg","channels":["depth"]})", ErrorCode::kBadField,
       "format raw or exr only"},
      {R"({"cmd":"render","view":"a","channels":["height"]})", ErrorCode::kBadField,
       "colour, coverage, depth, cloud_depth, object_id, visibility"},
      {R"({"cmd":"subscribe","view":"a","rate":1000})", ErrorCode::kBadField, "0.01 to 60"},
      {R"({"cmd":"snapshot","name":"a/b"})", ErrorCode::kBadField, "is not a name"},
      {R"({"cmd":"snapshot","name":".hidden"})", ErrorCode::kBadField, "not starting with"},
      {R"({"cmd":"hash","id":{"a":1}})", ErrorCode::kBadField, "id: must be"},
      {R"({"cmd":"render"})", ErrorCode::kBadField, "one of view and views"},
      {R"({"cmd":"render","view":"a","views":["b"]})", ErrorCode::kBadField, "one of view"},
      {R"({"cmd":"render","views":[]})", ErrorCode::kBadField, "1 to 16"},
      {R"({"cmd":"render","views":["a","a"]})", ErrorCode::kBadField, "repeated"},
      {R"({"cmd":"render","views":["a","b"],"camera":{}})", ErrorCode::kBadField, "one view"},
      {R"({"cmd":"render","view":"a","camera":{"vfov":0}})", ErrorCode::kBadField, "camera.vfov"},
      {R"({"cmd":"render","view":"a","camera":{"speed":1}})", ErrorCode::kBadField,
       "camera.speed: unknown field"},
      {R"({"cmd":"set_fog","enabled":false,"top":3})", ErrorCode::kBadField, "removes the fog"},
      {R"({"cmd":"set_haze","enabled":false,"scale_height":300})", ErrorCode::kBadField,
       "removes the haze"},
      {R"({"cmd":"set_haze","visibility":2})", ErrorCode::kBadField, "10 to 1e+07"},
      {R"({"cmd":"set_haze","colour":[1,1,1]})", ErrorCode::kBadField, "colour"},
      {R"({"cmd":"set_fog","visibility":0.5})", ErrorCode::kBadField, "1 to 1e+07"},
      {R"({"cmd":"set_sun","utc":"yesterday"})", ErrorCode::kBadField, "YYYY-MM-DD"},
      {R"({"cmd":"set_sun","utc":"2026-01-01T00:00Z","elevation":3})", ErrorCode::kBadField,
       "not both"},
      {R"({"cmd":"set_time","mode":"fast"})", ErrorCode::kBadField, "realtime, lockstep"},
      {R"({"cmd":"add_target"})", ErrorCode::kBadField, "[[target]]"},
      {R"({"cmd":"move_target","name":"t","pitch":91})", ErrorCode::kBadField, "-90 to 90"},
  };
  for (const Case& c : cases) {
    const BadRequest bad = rejected(c.line);
    EXPECT_EQ(bad.error.code, c.code) << c.line;
    EXPECT_THAT(bad.error.message, HasSubstr(c.words)) << c.line;
  }
  EXPECT_EQ(rejected(R"({"id":12,"cmd":"fly"})").id, 12);  // the id comes back when readable
}

// Issue 12, case 13: JSON the protocol must refuse though a lenient parser reads it.
TEST(Messages, RefusesByteOrderMarksDuplicateKeysAndTrailingBytes) {
  const std::string nul_after = std::string(R"({"cmd":"hash"})") + '\0';
  const std::pair<std::string, const char*> cases[] = {
      {"\xEF\xBB\xBF{\"cmd\":\"hash\"}", "byte-order mark"},
      {R"({"cmd":"tick","dt":1,"dt":2})", "duplicate key \"dt\""},
      {R"({"cmd":"add_cloud","cloud":{"name":"a","name":"b"}})", "duplicate key \"name\""},
      {R"({"cmd":"hash"} trailing)", "not valid JSON"},
      {nul_after, "not valid JSON"},
  };
  for (const auto& [line, words] : cases) {
    const BadRequest bad = rejected(line);
    EXPECT_EQ(bad.error.code, ErrorCode::kBadJson) << line;
    EXPECT_THAT(bad.error.message, HasSubstr(words)) << line;
  }
  // The same key in two different objects is fine.
  parsed(
      R"({"cmd":"add_cloud","cloud":{"name":"a","ellipsoid":[{"centre":[0,0,1000]},{"centre":[0,0,1200]}]}})");
}

TEST(Messages, LimitsOnSizeAndNesting) {
  const std::string big =
      R"({"cmd":"hash","pad":")" + std::string(ProtocolLimits::kMaxRequestBytes, 'x') + "\"}";
  EXPECT_EQ(rejected(big).error.code, ErrorCode::kTooLarge);
  std::string deep = std::string(ProtocolLimits::kMaxJsonDepth + 1, '[') +
                     std::string(ProtocolLimits::kMaxJsonDepth + 1, ']');
  EXPECT_THAT(rejected(deep).error.message, HasSubstr("nests deeper"));
  // Brackets inside strings do not count.
  parsed(R"({"cmd":"hello","token":"[[[[[[[[[[[[[[[[[[[[[[["})");
}

TEST(Messages, RepliesAreOneLineEach) {
  const std::string ok = okReply(5, {{"a", 1}});
  EXPECT_EQ(ok, "{\"id\":5,\"ok\":true,\"result\":{\"a\":1}}\n");
  const std::string error = errorReply(nullptr, {ErrorCode::kBusy, "full\nqueue"});
  EXPECT_EQ(std::count(error.begin(), error.end(), '\n'), 1);
  EXPECT_THAT(error, HasSubstr("\"code\":\"busy\""));
  const std::string header = imageReplyHeader("x", {{"width", 2}}, 16);
  EXPECT_THAT(header, HasSubstr("\"bytes\":16"));
  // Invalid UTF-8 in a message is replaced, never thrown.
  EXPECT_NO_THROW(errorReply(1, {ErrorCode::kBadField, "\xff\xfe"}));
}

}  // namespace
}  // namespace nephele
