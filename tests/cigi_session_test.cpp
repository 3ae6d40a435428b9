#include "protocol/cigi_session.h"

#include <bit>
#include <cstring>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "protocol/cigi.h"

// CIGI 3.3's sea packets: Maritime Surface Conditions Control (13) and Wave Control (14) as the
// ICD lays them out (written here byte by byte, not with the codec), and what a session makes of
// them. The daemon's end-to-end test (tests/daemon/cigi_test.py) checks the same bytes against
// Wireshark's dissector.
namespace nephele::cigi {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// Bytes of a packet in a byte order, field by field at the ICD's offsets.
class Bytes {
 public:
  Bytes(std::size_t size, bool big) : bytes_(size, 0), big_(big) {}
  template <class T>
  Bytes& put(std::size_t at, T value) {
    using U = std::conditional_t<sizeof(T) == 1, std::uint8_t,
                                 std::conditional_t<sizeof(T) == 2, std::uint16_t, std::uint32_t>>;
    const U u = std::bit_cast<U>(value);
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      const std::uint8_t b = std::uint8_t(u >> (8 * i));  // least significant first
      bytes_[at + (big_ ? sizeof(T) - 1 - i : i)] = b;
    }
    return *this;
  }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  std::vector<std::uint8_t> bytes_;
  bool big_;
};

std::vector<std::uint8_t> igControl(std::uint32_t frame, bool big) {
  Bytes b(24, big);
  b.put<std::uint8_t>(0, 1).put<std::uint8_t>(1, 24).put<std::uint8_t>(2, 3);
  b.put<std::uint8_t>(4, 1 | (3 << 4)).put<std::uint16_t>(6, 0x8000).put<std::uint32_t>(8, frame);
  return b.bytes();
}

// Maritime Surface Conditions Control: entity/region id at 2, at 4 the surface conditions
// enable (bit 0), whitecap enable (bit 1) and scope (bits 2-3); floats at 8 (sea surface
// height), 12 (water temperature) and 16 (clarity); 20-23 reserved.
std::vector<std::uint8_t> maritime(bool enabled, bool whitecaps, float temperature, float clarity,
                                   float height = 0.0f, int scope = 0, std::uint16_t id = 0,
                                   bool big = true) {
  Bytes b(24, big);
  b.put<std::uint8_t>(0, 13).put<std::uint8_t>(1, 24).put<std::uint16_t>(2, id);
  b.put<std::uint8_t>(4, std::uint8_t(int(enabled) | int(whitecaps) << 1 | scope << 2));
  b.put<float>(8, height).put<float>(12, temperature).put<float>(16, clarity);
  return b.bytes();
}

// Wave Control: entity/region id at 2, wave id at 4, at 5 the wave enable (bit 0), scope (bits
// 1-2) and breaker type (bits 3-4); floats at 8 (height), 12 (wavelength), 16 (period), 20
// (direction), 24 (phase offset) and 28 (leading).
struct Wave {
  std::uint8_t id = 0;
  bool enabled = true;
  float height = 1.0f, wavelength = 100.0f, period = 0.0f, direction = 0.0f, phase = 0.0f,
        leading = 0.0f;
  int breaker = 0, scope = 0;
  std::uint16_t region = 0;
};
std::vector<std::uint8_t> wave(const Wave& w, bool big = true) {
  Bytes b(32, big);
  b.put<std::uint8_t>(0, 14).put<std::uint8_t>(1, 32).put<std::uint16_t>(2, w.region);
  b.put<std::uint8_t>(4, w.id);
  b.put<std::uint8_t>(5, std::uint8_t(int(w.enabled) | w.scope << 1 | w.breaker << 3));
  b.put<float>(8, w.height).put<float>(12, w.wavelength).put<float>(16, w.period);
  b.put<float>(20, w.direction).put<float>(24, w.phase).put<float>(28, w.leading);
  return b.bytes();
}

std::vector<std::uint8_t> message(std::uint32_t frame,
                                  std::initializer_list<std::vector<std::uint8_t>> packets,
                                  bool big = true) {
  std::vector<std::uint8_t> out = igControl(frame, big);
  for (const auto& p : packets) out.insert(out.end(), p.begin(), p.end());
  return out;
}

Message decoded(const std::vector<std::uint8_t>& bytes) {
  auto m = decodeHostMessage(bytes);
  EXPECT_TRUE(std::holds_alternative<Message>(m))
      << (std::holds_alternative<DecodeError>(m) ? std::get<DecodeError>(m).message : "");
  return std::holds_alternative<Message>(m) ? std::get<Message>(m) : Message{};
}

TEST(CigiCodec, SeaPacketsFollowTheIcdLayoutInEitherByteOrder) {
  for (const bool big : {true, false}) {
    const Wave w{7, true, 2.5f, 180.0f, 9.5f, 135.0f, -30.0f, 12.0f, 2, 1, 300};
    const std::vector<std::uint8_t> bytes =
        message(1, {maritime(true, true, 14.5f, 80.0f, 1.25f, 2, 42, big), wave(w, big)}, big);
    const Message m = decoded(bytes);
    EXPECT_EQ(m.order, big ? ByteOrder::kBig : ByteOrder::kLittle);
    ASSERT_EQ(m.packets.size(), 3u);
    const auto& sea = std::get<MaritimeSurfaceConditionsControl>(m.packets[1]);
    EXPECT_EQ(sea.entity_region_id, 42);
    EXPECT_TRUE(sea.surface_conditions_enabled);
    EXPECT_TRUE(sea.whitecaps);
    EXPECT_EQ(sea.scope, WeatherScope::kEntity);
    EXPECT_EQ(sea.sea_surface_height, 1.25f);
    EXPECT_EQ(sea.water_temperature, 14.5f);
    EXPECT_EQ(sea.clarity, 80.0f);
    const auto& train = std::get<WaveControl>(m.packets[2]);
    EXPECT_EQ(train.entity_region_id, 300);
    EXPECT_EQ(train.wave_id, 7);
    EXPECT_TRUE(train.enabled);
    EXPECT_EQ(train.scope, WeatherScope::kRegional);
    EXPECT_EQ(train.breaker, BreakerType::kSurging);
    EXPECT_EQ(train.height, 2.5f);
    EXPECT_EQ(train.wavelength, 180.0f);
    EXPECT_EQ(train.period, 9.5f);
    EXPECT_EQ(train.direction, 135.0f);
    EXPECT_EQ(train.phase_offset, -30.0f);
    EXPECT_EQ(train.leading, 12.0f);
    // Written again, the same bytes.
    std::vector<std::uint8_t> again;
    for (const Packet& p : m.packets) encode(p, m.order, again);
    EXPECT_EQ(again, bytes);
  }
  // A sea packet of the wrong size is malformed, as every packet Nephele reads.
  std::vector<std::uint8_t> short_wave = message(1, {wave({})});
  short_wave[24 + 1] = 24;
  short_wave.resize(short_wave.size() - 8);
  const auto refused = decodeHostMessage(short_wave);
  ASSERT_TRUE(std::holds_alternative<DecodeError>(refused));
  EXPECT_EQ(std::get<DecodeError>(refused).fault, Fault::kMalformed);
  EXPECT_THAT(std::get<DecodeError>(refused).message, HasSubstr("Wave Control"));
}

class SeaSession : public ::testing::Test {
 protected:
  SeaSession() : session_(SessionSettings{Site{51.5, -1.25}, {"front"}, {}}) {}

  // The set_sea commands of a host frame, which the daemon then applies.
  std::vector<command::SetSea> frame(std::initializer_list<std::vector<std::uint8_t>> packets) {
    auto mapped = session_.map(decoded(message(++frame_, packets)));
    EXPECT_TRUE(std::holds_alternative<MappedMessage>(mapped));
    if (!std::holds_alternative<MappedMessage>(mapped)) return {};
    last_ = std::get<MappedMessage>(mapped);
    session_.commit();
    std::vector<command::SetSea> out;
    for (const Command& c : last_.commands)
      if (const auto* sea = std::get_if<command::SetSea>(&c)) out.push_back(*sea);
    return out;
  }

  Session session_;
  std::uint32_t frame_ = 0;
  MappedMessage last_;
};

TEST_F(SeaSession, MaritimeSurfaceConditionsSetTheSeaWhenTheyChange) {
  auto seas = frame({maritime(true, false, 12.0f, 40.0f)});
  ASSERT_EQ(seas.size(), 1u);
  EXPECT_EQ(seas[0].enabled, true);
  EXPECT_EQ(*seas[0].temperature, 12.0);
  EXPECT_DOUBLE_EQ(*seas[0].clarity, 0.4);  // percent to 0..1
  EXPECT_EQ(seas[0].whitecaps, false);
  EXPECT_TRUE(last_.ignored.empty());
  // Hosts repeat their packets every frame: the same again is no command; another region id
  // of global scope is the same sea.
  EXPECT_TRUE(frame({maritime(true, false, 12.0f, 40.0f)}).empty());
  EXPECT_TRUE(frame({maritime(true, false, 12.0f, 40.0f, 0.0f, 0, 9)}).empty());
  seas = frame({maritime(true, true, 12.0f, 40.0f)});
  ASSERT_EQ(seas.size(), 1u);
  EXPECT_EQ(seas[0].whitecaps, true);
  // Disabled removes the sea, once.
  seas = frame({maritime(false, true, 99.0f, 500.0f)});
  ASSERT_EQ(seas.size(), 1u);
  EXPECT_EQ(seas[0].enabled, false);
  EXPECT_FALSE(seas[0].temperature || seas[0].clarity || seas[0].whitecaps);
  EXPECT_TRUE(frame({maritime(false, false, 0.0f, 0.0f)}).empty());
  EXPECT_TRUE(last_.refused.empty());
}

TEST_F(SeaSession, WhatIsNotModelledIsIgnoredWithItsReasonAndBadValuesAreRefused) {
  // A sea surface height other than 0: said once, while the host repeats it.
  auto seas = frame({maritime(true, true, 15.0f, 50.0f, 2.0f)});
  EXPECT_EQ(seas.size(), 1u);
  EXPECT_THAT(last_.ignored, ElementsAre(HasSubstr("sea surface height 2 m (the sea lies at the "
                                                   "database's Z = 0)")));
  frame({maritime(true, true, 15.0f, 50.0f, 2.0f)});
  EXPECT_TRUE(last_.ignored.empty());
  // Regional and entity scope: the sea is global.
  EXPECT_TRUE(frame({maritime(true, true, 5.0f, 10.0f, 0.0f, 1, 3),
                     wave({.id = 2, .scope = 2, .region = 8})})
                  .empty());
  EXPECT_THAT(last_.ignored,
              ElementsAre(HasSubstr("Maritime Surface Conditions Control of region 3: regional "
                                    "sea state is not modelled: the sea is global"),
                          HasSubstr("Wave Control 2 of entity 8: regional sea state is not "
                                    "modelled: the sea is global")));
  // Breaker type and leading are not modelled: said when they change, the train still applies.
  seas = frame({wave({.id = 4, .leading = 20.0f, .breaker = 1})});
  ASSERT_EQ(seas.size(), 1u);
  EXPECT_THAT(last_.ignored,
              ElementsAre(HasSubstr("Wave Control 4: breaker type 1 (not modelled"),
                          HasSubstr("Wave Control 4: leading 20 degrees (not modelled")));
  // Out of range: refused alone, nothing of it applied or remembered.
  EXPECT_TRUE(frame({maritime(true, true, 45.0f, 50.0f), wave({.id = 5, .height = 31.0f}),
                     wave({.id = 6, .wavelength = std::nanf("")})})
                  .empty());
  EXPECT_THAT(last_.refused,
              ElementsAre(HasSubstr("surface water temperature 45, surface clarity 50 (allowed: "
                                    "temperature -2 to 40 degrees C, clarity 0 to 100 %)"),
                          HasSubstr("Wave Control 5: height 31"), HasSubstr("Wave Control 6")));
  EXPECT_EQ(frame({maritime(true, true, 45.0f, 50.0f)}).size(), 0u);  // refused again
  EXPECT_EQ(last_.refused.size(), 1u);
  EXPECT_EQ(frame({maritime(true, true, 15.0f, 101.0f)}).size(), 0u);
  EXPECT_THAT(last_.refused, ElementsAre(HasSubstr("clarity 101")));
}

TEST_F(SeaSession, WaveControlSetsOneTrainEachAndADisabledSeaKeepsThemForLater) {
  // A train propagating towards 135 degrees (CIGI's direction is where it travels, as the
  // sea's): passed on as it is.
  auto seas = frame({wave({.id = 3,
                           .height = 2.0f,
                           .wavelength = 150.0f,
                           .period = 9.0f,
                           .direction = 135.0f,
                           .phase = 45.0f})});
  ASSERT_EQ(seas.size(), 1u);
  EXPECT_FALSE(seas[0].enabled.has_value());
  ASSERT_EQ(seas[0].waves.size(), 1u);
  const command::WavePatch& p = seas[0].waves[0];
  EXPECT_EQ(p.id, 3);
  EXPECT_EQ(p.enabled, true);
  EXPECT_EQ(*p.height, 2.0);
  EXPECT_EQ(*p.wavelength, 150.0);
  EXPECT_EQ(*p.period, 9.0);
  EXPECT_EQ(*p.direction, 135.0);
  EXPECT_EQ(*p.phase, 45.0);
  EXPECT_TRUE(frame({wave({.id = 3,
                           .height = 2.0f,
                           .wavelength = 150.0f,
                           .period = 9.0f,
                           .direction = 135.0f,
                           .phase = 45.0f})})
                  .empty());
  // Disabled removes the train, once.
  seas = frame({wave({.id = 3, .enabled = false})});
  ASSERT_EQ(seas.size(), 1u);
  EXPECT_EQ(seas[0].waves[0].enabled, false);
  EXPECT_TRUE(frame({wave({.id = 3, .enabled = false, .height = 7.0f})}).empty());

  // The host disables the sea: its trains wait, and come back with it.
  frame({maritime(false, false, 0.0f, 0.0f)});
  EXPECT_TRUE(frame({wave({.id = 1, .height = 0.5f}), wave({.id = 2, .height = 1.5f})}).empty());
  seas = frame({maritime(true, false, 20.0f, 90.0f)});
  ASSERT_EQ(seas.size(), 1u);
  ASSERT_EQ(seas[0].waves.size(), 2u);
  EXPECT_EQ(*seas[0].waves[0].height, 0.5);
  EXPECT_EQ(*seas[0].waves[1].height, 1.5);

  // At most eight trains at once: a ninth is refused until one is disabled.
  for (std::uint8_t id = 10; id < 16; ++id) EXPECT_EQ(frame({wave({.id = id})}).size(), 1u);
  EXPECT_TRUE(frame({wave({.id = 200})}).empty());
  EXPECT_THAT(last_.refused, ElementsAre(HasSubstr("Wave Control 200: the host's 8 other wave "
                                                   "trains are enabled (allowed: at most 8")));
  frame({wave({.id = 10, .enabled = false})});
  EXPECT_EQ(frame({wave({.id = 200})}).size(), 1u);

  // After the daemon refused a frame, the session sends the sea and its trains afresh.
  session_.forget();
  seas = frame({maritime(true, false, 20.0f, 90.0f), wave({.id = 1, .height = 0.5f})});
  EXPECT_EQ(seas.size(), 2u);
}

}  // namespace
}  // namespace nephele::cigi
