#include "protocol/register_map.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace nephele {
namespace {

using ::testing::HasSubstr;
using M = ModbusMap;

std::vector<std::uint16_t> floatWords(float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, 4);
  return {std::uint16_t(bits >> 16), std::uint16_t(bits & 0xffff)};
}

HoldingRegisters sample() {
  HostReadings s;
  s.position = {100.0, -2000.0, 1500.0};
  s.heading = 90.0;
  s.width = 640;
  s.height = 480;
  s.layers[1] = {CloudType::kCumulus, 1200.0, 800.0, 0.4, {}, {}, {}};
  return encodeHolding(s);
}

RegisterError writeError(int address, std::vector<std::uint16_t> values) {
  auto r = decodeHoldingWrite(sample(), address, values, "front");
  EXPECT_TRUE(std::holds_alternative<RegisterError>(r)) << address;
  return std::holds_alternative<RegisterError>(r) ? std::get<RegisterError>(r) : RegisterError{};
}

std::vector<Command> writeOk(int address, std::vector<std::uint16_t> values) {
  auto r = decodeHoldingWrite(sample(), address, values, "front");
  EXPECT_TRUE(std::holds_alternative<std::vector<Command>>(r))
      << (std::holds_alternative<RegisterError>(r) ? std::get<RegisterError>(r).message : "");
  return std::holds_alternative<std::vector<Command>>(r) ? std::get<std::vector<Command>>(r)
                                                         : std::vector<Command>{};
}

TEST(RegisterMap, FloatsAreHighWordFirst) {
  std::uint16_t r[2];
  putFloat(r, 1.0);
  EXPECT_EQ(r[0], 0x3F80);
  EXPECT_EQ(r[1], 0x0000);
  putFloat(r, -2.5);
  EXPECT_EQ(r[0], 0xC020);
  EXPECT_EQ(getFloat(r), -2.5f);
  const HoldingRegisters h = sample();
  EXPECT_EQ(getFloat(&h[M::kPositionY]), -2000.0f);
  EXPECT_EQ(h[M::kWidth], 640);
  EXPECT_EQ(h[M::kLayerStart + M::kLayerStride + M::kLayerType], 7);
  EXPECT_FLOAT_EQ(getFloat(&h[M::kLayerStart + M::kLayerStride + M::kLayerCoverage]), 40.0f);
}

TEST(RegisterMap, InputRegistersCarryWideCounters) {
  HostStatus s;
  s.frames = 0x12345678;
  s.ticks = 0x0102030405060708ull;
  const InputRegisters r = encodeInput(s);
  EXPECT_EQ(r[M::kFrames], 0x1234);
  EXPECT_EQ(r[M::kFrames + 1], 0x5678);
  EXPECT_EQ(r[M::kTicks], 0x0102);
  EXPECT_EQ(r[M::kTicks + 3], 0x0708);
}

TEST(RegisterMap, WritesBecomeOnlyTheTouchedChanges) {
  auto heading = writeOk(M::kHeading, floatWords(45.0f));
  ASSERT_EQ(heading.size(), 1u);
  const auto& view = std::get<command::SetView>(heading[0]);
  EXPECT_EQ(view.view, "front");
  EXPECT_EQ(*view.patch.heading, 45.0);
  EXPECT_FALSE(view.patch.position || view.patch.pitch || view.patch.width);

  // One coordinate of the position: the others keep their register values.
  auto moved = writeOk(M::kPositionZ, floatWords(250.0f));
  EXPECT_EQ(*std::get<command::SetView>(moved[0]).patch.position, glm::dvec3(100, -2000, 250));

  auto layer = writeOk(M::kLayerStart + M::kLayerType, {10});
  const auto& weather = std::get<command::SetWeather>(layer[0]);
  EXPECT_EQ(weather.layer, 1);
  EXPECT_EQ(weather.weather.type, CloudType::kStratus);

  // Sun and time scale in one write: two commands.
  std::vector<std::uint16_t> values = floatWords(10.0f);
  for (auto w : floatWords(2.0f)) values.push_back(w);
  auto both = writeOk(M::kSunElevation, values);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_EQ(*std::get<command::SetSun>(both[0]).elevation, 10.0);
  EXPECT_FALSE(std::get<command::SetSun>(both[0]).azimuth.has_value());
}

TEST(RegisterMap, BadWritesNameTheRegisterAndTheException) {
  EXPECT_EQ(writeError(M::kHeading, {0x7FC0, 0}).exception, kIllegalDataValue);  // NaN
  EXPECT_EQ(writeError(M::kHeading, {0x7F80, 0}).exception, kIllegalDataValue);  // infinity
  const RegisterError vfov = writeError(M::kVfov, floatWords(200.0f));
  EXPECT_THAT(vfov.message, HasSubstr("vfov (register 12)"));
  EXPECT_THAT(vfov.message, HasSubstr("0.01 to 179"));
  EXPECT_EQ(writeError(M::kHeight, {0}).exception, kIllegalDataValue);
  EXPECT_EQ(writeError(M::kLayerStart, {11}).exception, kIllegalDataValue);
  EXPECT_EQ(writeError(M::kPositionZ, floatWords(-1.0f)).exception, kIllegalDataValue);

  EXPECT_EQ(writeError(M::kHeading + 1, {1}).exception, kIllegalDataAddress);  // half a float
  const RegisterError half = writeError(M::kHeading, {0x4200});
  EXPECT_THAT(half.message, HasSubstr("half of the float32 at registers 6-7"));
  EXPECT_EQ(writeError(M::kTimeScale + 2, {1}).exception, kIllegalDataAddress);  // reserved
  EXPECT_EQ(writeError(M::kLayerStart + 7, {1}).exception, kIllegalDataAddress);
  EXPECT_EQ(writeError(M::kHoldingCount, {1}).exception, kIllegalDataAddress);
  EXPECT_EQ(writeError(M::kHoldingCount - 1, {1, 2}).exception, kIllegalDataAddress);
  // A good value beside a bad one: the whole write is refused.
  std::vector<std::uint16_t> mixed = floatWords(10.0f);
  for (auto w : floatWords(NAN)) mixed.push_back(w);
  EXPECT_EQ(writeError(M::kHeading, mixed).exception, kIllegalDataValue);
}

TEST(RegisterMap, Coils) {
  const std::uint8_t on[] = {1};
  auto render = std::get<CoilWrite>(decodeCoilWrite(M::kRenderCoil, on));
  EXPECT_TRUE(render.render);
  EXPECT_FALSE(render.paused.has_value());
  const std::uint8_t both[] = {0, 1};
  auto pause = std::get<CoilWrite>(decodeCoilWrite(0, both));
  EXPECT_FALSE(pause.render);
  EXPECT_TRUE(*pause.paused);
  EXPECT_EQ(std::get<RegisterError>(decodeCoilWrite(2, on)).exception, kIllegalDataAddress);
}

}  // namespace
}  // namespace nephele

namespace nephele {
namespace {

// Issue 29: the distance haze, set whole from registers 26-29; 0 removes it, a visibility
// under 10 m and a scale height out of range are refused with the register and the range.
TEST(RegisterMap, Haze) {
  std::uint16_t v[4];
  putFloat(v, 25000.0);
  putFloat(v + 2, 900.0);
  auto haze = decodeHoldingWrite(HoldingRegisters{}, ModbusMap::kHazeVisibility, v, "front");
  ASSERT_TRUE(std::holds_alternative<std::vector<Command>>(haze));
  const auto& set = std::get<command::SetHaze>(std::get<std::vector<Command>>(haze).at(0));
  EXPECT_EQ((std::tuple{*set.enabled, *set.visibility, *set.scale_height}),
            (std::tuple{true, 25000.0, 900.0}));
  putFloat(v, 0.0);
  auto none = decodeHoldingWrite(HoldingRegisters{}, ModbusMap::kHazeVisibility, v, "front");
  ASSERT_TRUE(std::holds_alternative<std::vector<Command>>(none));
  EXPECT_EQ(std::get<command::SetHaze>(std::get<std::vector<Command>>(none).at(0)).enabled, false);
  putFloat(v, 5.0);
  const auto low = decodeHoldingWrite(HoldingRegisters{}, ModbusMap::kHazeVisibility, v, "front");
  ASSERT_TRUE(std::holds_alternative<RegisterError>(low));
  EXPECT_NE(std::get<RegisterError>(low).message.find("register 26"), std::string::npos);
  putFloat(v, 25000.0);
  putFloat(v + 2, 5.0);
  const auto flat = decodeHoldingWrite(HoldingRegisters{}, ModbusMap::kHazeVisibility, v, "front");
  ASSERT_TRUE(std::holds_alternative<RegisterError>(flat));
  EXPECT_NE(std::get<RegisterError>(flat).message.find("haze scale height"), std::string::npos);
  // Registers 30-31 stay reserved.
  EXPECT_TRUE(std::holds_alternative<RegisterError>(
      decodeHoldingWrite(HoldingRegisters{}, 30, v, "front")));
}

// Issue 16: fog and the sun's date and time; a NaN time of day (found by protocol_fuzz) and a
// day that does not exist are refused.
TEST(RegisterMap, FogAndSunDate) {
  std::uint16_t v[4];
  putFloat(v, 150.0);
  putFloat(v + 2, 800.0);
  auto fog = decodeHoldingWrite(HoldingRegisters{}, ModbusMap::kFogTop, v, "front");
  ASSERT_TRUE(std::holds_alternative<std::vector<Command>>(fog));
  const auto& set = std::get<command::SetFog>(std::get<std::vector<Command>>(fog).at(0));
  EXPECT_EQ((std::pair{*set.top, *set.visibility}), (std::pair{150.0, 800.0}));
  const std::uint32_t date = 20260621;
  v[0] = std::uint16_t(date >> 16), v[1] = std::uint16_t(date & 0xffff);
  putFloat(v + 2, 3600.0 * 13 + 61.5);
  auto sun = decodeHoldingWrite(HoldingRegisters{}, ModbusMap::kSunDate, v, "front");
  ASSERT_TRUE(std::holds_alternative<std::vector<Command>>(sun));
  const CivilTime t = *std::get<command::SetSun>(std::get<std::vector<Command>>(sun).at(0)).utc;
  EXPECT_EQ((std::array{t.year, t.month, t.day, t.hour, t.minute}),
            (std::array{2026, 6, 21, 13, 1}));
  EXPECT_NEAR(t.second, 1.5, 1e-3);
  putFloat(v + 2, std::nan(""));
  EXPECT_TRUE(std::holds_alternative<RegisterError>(
      decodeHoldingWrite(HoldingRegisters{}, ModbusMap::kSunDate, v, "front")));
  const std::uint32_t bad = 20260230;
  v[0] = std::uint16_t(bad >> 16), v[1] = std::uint16_t(bad & 0xffff);
  putFloat(v + 2, 0.0);
  const auto refused = decodeHoldingWrite(HoldingRegisters{}, ModbusMap::kSunDate, v, "front");
  ASSERT_TRUE(std::holds_alternative<RegisterError>(refused));
  EXPECT_NE(std::get<RegisterError>(refused).message.find("day 30"), std::string::npos);
}

}  // namespace
}  // namespace nephele
