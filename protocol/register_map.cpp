#include "protocol/register_map.h"

#include <bit>
#include <cmath>
#include <sstream>

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
};
constexpr FloatField kLayerFloats[] = {
    {M::kLayerBase, "base", 0.0, Limits::kMaxBase},
    {M::kLayerThickness, "thickness", Limits::kThickness.lo, Limits::kThickness.hi},
    {M::kLayerCoverage, "coverage", Limits::kCoveragePercent.lo, Limits::kCoveragePercent.hi},
};

std::string formatNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Every float32 field's first register, for the half-a-float check.
std::vector<int> floatAddresses() {
  std::vector<int> out;
  for (const FloatField& f : kViewFloats) out.push_back(f.address);
  for (const FloatField& f : kOtherFloats) out.push_back(f.address);
  for (int layer = 0; layer < ProtocolLimits::kWeatherLayers; ++layer)
    for (const FloatField& f : kLayerFloats)
      out.push_back(M::kLayerStart + layer * M::kLayerStride + f.address);
  return out;
}

bool isReserved(int address) {
  if (address > M::kTimeScale + 1 && address < M::kLayerStart) return true;
  return address >= M::kLayerStart && (address - M::kLayerStart) % M::kLayerStride == 7;
}

struct Written {
  int first, end;  // [first, end)
  bool touches(int address, int count = 1) const {
    return address < end && address + count > first;
  }
};

}  // namespace

void putFloat(std::uint16_t* registers, double value) {
  const auto bits = std::bit_cast<std::uint32_t>(float(value));
  registers[0] = std::uint16_t(bits >> 16);
  registers[1] = std::uint16_t(bits & 0xffffu);
}

float getFloat(const std::uint16_t* registers) {
  return std::bit_cast<float>(std::uint32_t(registers[0]) << 16 | registers[1]);
}

HoldingRegisters encodeHolding(const ModbusSettings& s) {
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
  for (int layer = 0; layer < ProtocolLimits::kWeatherLayers; ++layer) {
    std::uint16_t* b = &r[std::size_t(M::kLayerStart + layer * M::kLayerStride)];
    const WeatherLayer& w = s.layers[std::size_t(layer)];
    b[M::kLayerType] = std::uint16_t(w.type);
    putFloat(b + M::kLayerBase, w.base_m);
    putFloat(b + M::kLayerThickness, w.thickness_m);
    putFloat(b + M::kLayerCoverage, w.coverage * 100.0);
  }
  return r;
}

InputRegisters encodeInput(const ModbusStatus& s) {
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
  std::optional<RegisterError> error;
  // The value of a touched float field, checked against its range.
  auto readFloat = [&](const FloatField& f, int base) -> double {
    const double v = getFloat(&next[std::size_t(base + f.address)]);
    if (!error && !(std::isfinite(v) && v >= f.lo && v <= f.hi))
      error = RegisterError{kIllegalDataValue,
                            std::string(f.name) + " (register " + std::to_string(base + f.address) +
                                "): " + formatNumber(v) + " is out of range (allowed: " +
                                formatNumber(f.lo) + " to " + formatNumber(f.hi) + ")"};
    return v;
  };

  std::vector<Command> commands;
  command::SetView set_view{view, {}};
  ViewPatch& p = set_view.patch;
  glm::dvec3 position{0.0};
  bool moved = false;
  for (int i = 0; i < 3; ++i)
    if (w.touches(kViewFloats[i].address, 2)) {
      position[i] = readFloat(kViewFloats[i], 0);
      moved = true;
    }
  if (moved) {
    for (int i = 0; i < 3; ++i)
      if (!w.touches(kViewFloats[i].address, 2))
        position[i] = getFloat(&next[std::size_t(kViewFloats[i].address)]);
    p.position = position;
  }
  std::optional<double>* angles[] = {&p.heading, &p.pitch, &p.roll, &p.vfov};
  for (int i = 3; i < 7; ++i)
    if (w.touches(kViewFloats[i].address, 2)) *angles[i - 3] = readFloat(kViewFloats[i], 0);
  for (auto [a, out, name] :
       {std::tuple{M::kWidth, &p.width, "width"}, std::tuple{M::kHeight, &p.height, "height"}})
    if (w.touches(a)) {
      if (!error && (next[std::size_t(a)] < 1 || next[std::size_t(a)] > Limits::kMaxImageSide))
        error =
            RegisterError{kIllegalDataValue, std::string(name) + " (register " + std::to_string(a) +
                                                 "): " + std::to_string(next[std::size_t(a)]) +
                                                 " is out of range (allowed: 1 to " +
                                                 std::to_string(Limits::kMaxImageSide) + ")"};
      *out = next[std::size_t(a)];
    }
  if (w.touches(0, M::kHeight + 1)) commands.emplace_back(set_view);

  if (w.touches(M::kWindEast, 4)) {
    const glm::dvec2 wind(readFloat(kOtherFloats[0], 0), readFloat(kOtherFloats[1], 0));
    if (!error && glm::length(wind) > Limits::kMaxWind)
      error = RegisterError{kIllegalDataValue, "wind: speed above 200 m/s"};
    commands.emplace_back(command::SetWind{wind});
  }
  if (w.touches(M::kSunAzimuth, 4)) {
    command::SetSun sun;
    if (w.touches(M::kSunAzimuth, 2)) sun.azimuth = readFloat(kOtherFloats[2], 0);
    if (w.touches(M::kSunElevation, 2)) sun.elevation = readFloat(kOtherFloats[3], 0);
    commands.emplace_back(sun);
  }
  if (w.touches(M::kTimeScale, 2))
    commands.emplace_back(command::SetTime{readFloat(kOtherFloats[4], 0), {}, {}});

  for (int layer = 0; layer < ProtocolLimits::kWeatherLayers; ++layer) {
    const int base = M::kLayerStart + layer * M::kLayerStride;
    if (!w.touches(base, M::kLayerStride)) continue;
    command::SetWeather set{layer + 1, {}};
    const std::uint16_t type = next[std::size_t(base + M::kLayerType)];
    if (!error && type >= kCloudTypeCount)
      error = RegisterError{kIllegalDataValue,
                            "layer " + std::to_string(layer + 1) + " cloud type (register " +
                                std::to_string(base) + "): " + std::to_string(type) +
                                " is out of range (allowed: 0 to 10, CIGI cloud types)"};
    set.weather.type = CloudType(type);
    set.weather.base_m = readFloat(kLayerFloats[0], base);
    set.weather.thickness_m = readFloat(kLayerFloats[1], base);
    set.weather.coverage = readFloat(kLayerFloats[2], base) / 100.0;
    commands.emplace_back(set);
  }
  if (error) return *error;
  return commands;
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
