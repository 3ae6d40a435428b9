#include "protocol/register_map.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>

#include "protocol/cloud_codes.h"
#include "world/limits.h"

namespace nephele {
namespace {

using M = ModbusMap;

// A float32 field of the holding map: address, name and allowed range.
struct FloatField {
  int address;
  const char* name;
  double lo, hi;
};

constexpr FloatField kViewFloats[] = {
    {M::kPositionX, "position x", -Limits::kMaxCoordinate, Limits::kMaxCoordinate},
    {M::kPositionY, "position y", -Limits::kMaxCoordinate, Limits::kMaxCoordinate},
    {M::kPositionZ, "position z", 0.0, Limits::kMaxCoordinate},
    {M::kHeading, "heading", -Limits::kMaxHeading, Limits::kMaxHeading},
    {M::kPitch, "pitch", -Limits::kMaxPitch, Limits::kMaxPitch},
    {M::kRoll, "roll", -Limits::kMaxRoll, Limits::kMaxRoll},
    {M::kVfov, "vfov", Limits::kMinVfov, Limits::kMaxVfov},
};
constexpr FloatField kOtherFloats[] = {
    {M::kWindEast, "wind east", -Limits::kMaxWind, Limits::kMaxWind},
    {M::kWindNorth, "wind north", -Limits::kMaxWind, Limits::kMaxWind},
    {M::kSunAzimuth, "sun azimuth", -Limits::kMaxHeading, Limits::kMaxHeading},
    {M::kSunElevation, "sun elevation", -Limits::kMaxPitch, Limits::kMaxPitch},
    {M::kTimeScale, "time scale", 0.0, ProtocolLimits::kMaxTimeScale},
    {M::kHazeVisibility, "haze visibility", 0.0, Limits::kHazeVisibility.hi},
    {M::kHazeScaleHeight, "haze scale height", Limits::kHazeScaleHeight.lo,
     Limits::kHazeScaleHeight.hi},
};
constexpr FloatField kAtmosphereFloats[] = {
    {M::kFogTop, "fog top", 0.0, Limits::kMaxAltitude},
    {M::kFogVisibility, "fog visibility", 0.0, Limits::kFogVisibility.hi},
    {M::kSunTime, "sun time of day", 0.0, 86399.999},
    {M::kFogColour, "fog red", Limits::kColour.lo, Limits::kColour.hi},
    {M::kFogColour + 2, "fog green", Limits::kColour.lo, Limits::kColour.hi},
    {M::kFogColour + 4, "fog blue", Limits::kColour.lo, Limits::kColour.hi},
};
constexpr FloatField kLayerFloats[] = {
    {M::kLayerBase, "base", 0.0, Limits::kMaxBase},
    {M::kLayerThickness, "thickness", Limits::kThickness.lo, Limits::kThickness.hi},
    {M::kLayerCoverage, "coverage", Limits::kCoveragePercent.lo, Limits::kCoveragePercent.hi},
};

// Every float32 field's first register, for the half-a-float check.
std::vector<int> floatAddresses() {
  std::vector<int> out;
  for (const FloatField& f : kViewFloats) out.push_back(f.address);
  for (const FloatField& f : kOtherFloats) out.push_back(f.address);
  for (const FloatField& f : kAtmosphereFloats) out.push_back(f.address);
  out.push_back(M::kSunDate);  // a uint32, written whole like a float
  for (int layer = 0; layer < ProtocolLimits::kWeatherLayers; ++layer)
    for (const FloatField& f : kLayerFloats)
      out.push_back(M::kLayerStart + layer * M::kLayerStride + f.address);
  return out;
}

// A visibility register where 0 removes the medium (fog, haze): none, or the error for a value
// between 0 and the range (readFloat has checked the rest).
std::optional<RegisterError> zeroOrWithin(const char* medium, int address, double visibility,
                                          Range range) {
  if (visibility == 0.0 || visibility >= range.lo) return std::nullopt;
  return RegisterError{kIllegalDataValue,
                       std::string(medium) + " visibility (register " + std::to_string(address) +
                           "): " + formatNumber(visibility) +
                           " is out of range (allowed: 0 for no " + medium + ", or " +
                           formatNumber(range.lo) + " to " + formatNumber(range.hi) + ")"};
}

bool isReserved(int address) {
  if (address > M::kHazeScaleHeight + 1 && address < M::kLayerStart) return true;
  return address >= M::kLayerStart && address < M::kFogTop &&
         (address - M::kLayerStart) % M::kLayerStride == 7;
}

struct Written {
  int first, end;  // [first, end)
  bool touches(int address, int count = 1) const {
    return address < end && address + count > first;
  }
};

// A write's registers as commands, in the map's order: the view, the wind, the sun's angles,
// the time scale, the weather layers, the fog, the haze and the sun's date. Each group the
// write touches becomes its command; the first value out of range is the write's error.
class HoldingWrite {
 public:
  HoldingWrite(const HoldingRegisters& registers, Written written)
      : next_(registers), w_(written) {}

  void viewSettings(const std::string& view);
  void wind();
  void sunAngles();
  void timeScale();
  void weatherLayer(int layer);
  void fog();
  void haze();
  void sunDate();
  std::variant<std::vector<Command>, RegisterError> result() && {
    if (error_) return *error_;
    return std::move(commands_);
  }

 private:
  // The value of a touched float field, checked against its range.
  double readFloat(const FloatField& f, int base = 0) {
    const double v = getFloat(&next_[std::size_t(base + f.address)]);
    if (!error_ && !(std::isfinite(v) && v >= f.lo && v <= f.hi))
      error_ = RegisterError{kIllegalDataValue,
                             std::string(f.name) + " (register " +
                                 std::to_string(base + f.address) + "): " + formatNumber(v) +
                                 " is out of range (allowed: " + formatNumber(f.lo) + " to " +
                                 formatNumber(f.hi) + ")"};
    return v;
  }
  void fail(std::optional<RegisterError> error) {
    if (!error_) error_ = std::move(error);
  }

  const HoldingRegisters& next_;
  const Written w_;
  std::vector<Command> commands_;
  std::optional<RegisterError> error_;
};

// The view's position (set whole when any coordinate is written), angles, field of view and
// image size.
void HoldingWrite::viewSettings(const std::string& view) {
  command::SetView set_view{view, {}};
  ViewPatch& p = set_view.patch;
  glm::dvec3 position{0.0};
  bool moved = false;
  for (int i = 0; i < 3; ++i)
    if (w_.touches(kViewFloats[i].address, 2)) {
      position[i] = readFloat(kViewFloats[i]);
      moved = true;
    }
  if (moved) {
    for (int i = 0; i < 3; ++i)
      if (!w_.touches(kViewFloats[i].address, 2))
        position[i] = getFloat(&next_[std::size_t(kViewFloats[i].address)]);
    p.position = position;
  }
  std::optional<double>* angles[] = {&p.heading, &p.pitch, &p.roll, &p.vfov};
  for (int i = 3; i < 7; ++i)
    if (w_.touches(kViewFloats[i].address, 2)) *angles[i - 3] = readFloat(kViewFloats[i]);
  for (auto [a, out, name] :
       {std::tuple{M::kWidth, &p.width, "width"}, std::tuple{M::kHeight, &p.height, "height"}})
    if (w_.touches(a)) {
      if (next_[std::size_t(a)] < 1 || next_[std::size_t(a)] > Limits::kMaxImageSide)
        fail(RegisterError{kIllegalDataValue, std::string(name) + " (register " +
                                                  std::to_string(a) +
                                                  "): " + std::to_string(next_[std::size_t(a)]) +
                                                  " is out of range (allowed: 1 to " +
                                                  std::to_string(Limits::kMaxImageSide) + ")"});
      *out = next_[std::size_t(a)];
    }
  if (w_.touches(0, M::kHeight + 1)) commands_.emplace_back(set_view);
}

void HoldingWrite::wind() {
  if (!w_.touches(M::kWindEast, 4)) return;
  const glm::dvec2 wind(readFloat(kOtherFloats[0]), readFloat(kOtherFloats[1]));
  if (glm::length(wind) > Limits::kMaxWind)
    fail(RegisterError{kIllegalDataValue, "wind: speed above 200 m/s"});
  commands_.emplace_back(command::SetWind{wind});
}

void HoldingWrite::sunAngles() {
  if (!w_.touches(M::kSunAzimuth, 4)) return;
  command::SetSun sun;
  if (w_.touches(M::kSunAzimuth, 2)) sun.azimuth = readFloat(kOtherFloats[2]);
  if (w_.touches(M::kSunElevation, 2)) sun.elevation = readFloat(kOtherFloats[3]);
  commands_.emplace_back(sun);
}

void HoldingWrite::timeScale() {
  if (w_.touches(M::kTimeScale, 2))
    commands_.emplace_back(command::SetTime{readFloat(kOtherFloats[4]), {}, {}, {}});
}

// Weather layer `layer` + 1, set whole when any of its registers is written.
void HoldingWrite::weatherLayer(int layer) {
  const int base = M::kLayerStart + layer * M::kLayerStride;
  if (!w_.touches(base, M::kLayerStride)) return;
  command::SetWeather set{layer + 1, {}, std::nullopt};
  const std::uint16_t type = next_[std::size_t(base + M::kLayerType)];
  const std::optional<CloudType> genus = cloudTypeFromCode(type);
  if (!genus)
    fail(RegisterError{kIllegalDataValue,
                       "layer " + std::to_string(layer + 1) + " cloud type (register " +
                           std::to_string(base) + "): " + std::to_string(type) +
                           " is out of range (allowed: " + cloudTypeCodesAllowed() +
                           ", CIGI cloud types)"});
  set.weather.type = genus.value_or(CloudType::kNone);
  set.weather.base_m = readFloat(kLayerFloats[0], base);
  set.weather.thickness_m = readFloat(kLayerFloats[1], base);
  set.weather.coverage = readFloat(kLayerFloats[2], base) / 100.0;
  commands_.emplace_back(set);
}

// The fog, set whole: its top, visibility (0: none) and colour.
void HoldingWrite::fog() {
  if (!(w_.touches(M::kFogTop, 4) || w_.touches(M::kFogColour, 6))) return;
  const double top = readFloat(kAtmosphereFloats[0]);
  const double visibility = readFloat(kAtmosphereFloats[1]);
  const glm::dvec3 colour(readFloat(kAtmosphereFloats[3]), readFloat(kAtmosphereFloats[4]),
                          readFloat(kAtmosphereFloats[5]));
  if (!error_) error_ = zeroOrWithin("fog", M::kFogVisibility, visibility, Limits::kFogVisibility);
  if (visibility == 0.0)
    commands_.emplace_back(command::SetFog{false, {}, {}, {}});
  else
    commands_.emplace_back(command::SetFog{true, top, visibility, colour});
}

// The haze, set whole: its visibility (0: none) and scale height.
void HoldingWrite::haze() {
  if (!w_.touches(M::kHazeVisibility, 4)) return;
  const double visibility = readFloat(kOtherFloats[5]);
  const double scale_height = readFloat(kOtherFloats[6]);
  if (!error_)
    error_ = zeroOrWithin("haze", M::kHazeVisibility, visibility, Limits::kHazeVisibility);
  if (visibility == 0.0)
    commands_.emplace_back(command::SetHaze{false, {}, {}});
  else
    commands_.emplace_back(command::SetHaze{true, visibility, scale_height});
}

// The sun placed by a UTC date and time of day at [site]; date 0 leaves it where the angles
// put it. Written only when every value so far is in range (the seconds are checked).
void HoldingWrite::sunDate() {
  if (!w_.touches(M::kSunDate, 4)) return;
  const std::uint32_t date = std::uint32_t(next_[M::kSunDate]) << 16 | next_[M::kSunDate + 1];
  const double seconds = readFloat(kAtmosphereFloats[2]);
  if (date == 0 || error_) return;
  CivilTime t;
  t.year = int(date / 10000);
  t.month = int(date / 100 % 100);
  t.day = int(date % 100);
  const double s = std::floor(std::clamp(seconds, 0.0, 86399.999));
  t.hour = int(s / 3600.0);
  t.minute = int((s - t.hour * 3600.0) / 60.0);
  t.second = std::clamp(seconds - t.hour * 3600.0 - t.minute * 60.0, 0.0, 59.999);
  if (std::string e = civilTimeError(t); !e.empty())
    fail(RegisterError{kIllegalDataValue, "sun date (registers " + std::to_string(M::kSunDate) +
                                              "-" + std::to_string(M::kSunDate + 1) +
                                              ", YYYYMMDD): " + e});
  commands_.emplace_back(command::SetSun{std::nullopt, std::nullopt, t, std::nullopt});
}

}  // namespace

void putFloat(std::uint16_t* registers, double value) {
  const auto bits = std::bit_cast<std::uint32_t>(float(value));
  registers[0] = std::uint16_t(bits >> 16);
  registers[1] = std::uint16_t(bits & 0xffffu);
}

float getFloat(const std::uint16_t* registers) {
  return std::bit_cast<float>(std::uint32_t(registers[0]) << 16 | registers[1]);
}

HoldingRegisters encodeHolding(const HostReadings& s) {
  HoldingRegisters r{};
  for (int i = 0; i < 3; ++i) putFloat(&r[std::size_t(M::kPositionX + 2 * i)], s.position[i]);
  putFloat(&r[M::kHeading], s.heading);
  putFloat(&r[M::kPitch], s.pitch);
  putFloat(&r[M::kRoll], s.roll);
  putFloat(&r[M::kVfov], s.vfov);
  r[M::kWidth] = std::uint16_t(s.width);
  r[M::kHeight] = std::uint16_t(s.height);
  putFloat(&r[M::kWindEast], s.wind.x);
  putFloat(&r[M::kWindNorth], s.wind.y);
  putFloat(&r[M::kSunAzimuth], s.sun_azimuth);
  putFloat(&r[M::kSunElevation], s.sun_elevation);
  putFloat(&r[M::kTimeScale], s.time_scale);
  putFloat(&r[M::kHazeVisibility], s.haze_visibility);
  putFloat(&r[M::kHazeScaleHeight], s.haze_scale_height);
  for (int layer = 0; layer < ProtocolLimits::kWeatherLayers; ++layer) {
    std::uint16_t* b = &r[std::size_t(M::kLayerStart + layer * M::kLayerStride)];
    const WeatherLayer& w = s.layers[std::size_t(layer)];
    b[M::kLayerType] = std::uint16_t(cloudTypeCode(w.type));
    putFloat(b + M::kLayerBase, w.base_m);
    putFloat(b + M::kLayerThickness, w.thickness_m);
    putFloat(b + M::kLayerCoverage, w.coverage * 100.0);
  }
  putFloat(&r[M::kFogTop], s.fog_top);
  putFloat(&r[M::kFogVisibility], s.fog_visibility);
  for (int i = 0; i < 3; ++i) putFloat(&r[std::size_t(M::kFogColour + 2 * i)], s.fog_colour[i]);
  if (s.sun_utc) {
    const CivilTime& t = *s.sun_utc;
    const std::uint32_t date = std::uint32_t(t.year * 10000 + t.month * 100 + t.day);
    r[M::kSunDate] = std::uint16_t(date >> 16);
    r[M::kSunDate + 1] = std::uint16_t(date & 0xffffu);
    putFloat(&r[M::kSunTime], t.hour * 3600.0 + t.minute * 60.0 + t.second);
  }
  return r;
}

InputRegisters encodeInput(const HostStatus& s) {
  InputRegisters r{};
  r[M::kStatus] = std::uint16_t(s.status);
  r[M::kFrames] = std::uint16_t(s.frames >> 16);
  r[M::kFrames + 1] = std::uint16_t(s.frames & 0xffffu);
  putFloat(&r[M::kRenderMs], s.render_ms);
  for (int i = 0; i < 4; ++i)
    r[std::size_t(M::kTicks + i)] = std::uint16_t(s.ticks >> (48 - 16 * i));
  r[M::kLastError] = s.last_error;
  putFloat(&r[M::kTime], s.time_s);
  return r;
}

std::variant<std::vector<Command>, RegisterError> decodeHoldingWrite(
    const HoldingRegisters& current, int address, std::span<const std::uint16_t> values,
    const std::string& view) {
  const int count = int(values.size());
  if (address < 0 || count < 1 || address + count > M::kHoldingCount)
    return RegisterError{kIllegalDataAddress, "holding registers " + std::to_string(address) +
                                                  " to " + std::to_string(address + count - 1) +
                                                  " are outside the map (allowed: 0 to " +
                                                  std::to_string(M::kHoldingCount - 1) + ")"};
  for (int a = address; a < address + count; ++a)
    if (isReserved(a))
      return RegisterError{kIllegalDataAddress,
                           "holding register " + std::to_string(a) + " is reserved"};
  const Written w{address, address + count};
  for (int f : floatAddresses())
    if (w.touches(f) != w.touches(f + 1))
      return RegisterError{kIllegalDataAddress,
                           "the write covers half of the float32 at registers " +
                               std::to_string(f) + "-" + std::to_string(f + 1) +
                               " (write both registers in one request)"};
  HoldingRegisters next = current;
  std::copy(values.begin(), values.end(), next.begin() + address);
  HoldingWrite write(next, w);
  write.viewSettings(view);
  write.wind();
  write.sunAngles();
  write.timeScale();
  for (int layer = 0; layer < ProtocolLimits::kWeatherLayers; ++layer) write.weatherLayer(layer);
  write.fog();
  write.haze();
  write.sunDate();
  return std::move(write).result();
}

std::variant<CoilWrite, RegisterError> decodeCoilWrite(int address,
                                                       std::span<const std::uint8_t> bits) {
  const int count = int(bits.size());
  if (address < 0 || count < 1 || address + count > M::kCoilCount)
    return RegisterError{kIllegalDataAddress, "coils " + std::to_string(address) + " to " +
                                                  std::to_string(address + count - 1) +
                                                  " are outside the map (allowed: 0 to " +
                                                  std::to_string(M::kCoilCount - 1) + ")"};
  CoilWrite out;
  for (int i = 0; i < count; ++i) {
    const bool on = bits[std::size_t(i)] != 0;
    if (address + i == M::kRenderCoil) out.render = on;
    if (address + i == M::kPauseCoil) out.paused = on;
  }
  return out;
}

}  // namespace nephele
