#include "protocol/cigi.h"

#include <bit>
#include <optional>
#include <type_traits>

namespace nephele::cigi {
namespace {

// The unsigned integer of `N` bytes.
template <std::size_t N>
using Unsigned = std::conditional_t<
    N == 1, std::uint8_t,
    std::conditional_t<N == 2, std::uint16_t,
                       std::conditional_t<N == 4, std::uint32_t, std::uint64_t>>>;

// Reads or writes one packet's fields at their byte offsets (from the packet's start), in the
// message's byte order. Each packet's layout is written once, below, and serves both ways.
class Reader {
 public:
  Reader(const std::uint8_t* p, ByteOrder order) : p_(p), order_(order) {}
  template <class T>
  void number(std::size_t at, T& value) {
    using U = Unsigned<sizeof(T)>;
    U u = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      const std::size_t k = order_ == ByteOrder::kBig ? i : sizeof(T) - 1 - i;
      u = U(U(u << 8) | p_[at + k]);
    }
    value = std::bit_cast<T>(u);
  }
  // `width` bits from bit `shift` (0 the least significant) of the byte at `at`.
  template <class T>
  void bits(std::size_t at, int shift, int width, T& value) {
    value = T((p_[at] >> shift) & ((1 << width) - 1));
  }

 private:
  const std::uint8_t* p_;
  ByteOrder order_;
};

class Writer {
 public:
  Writer(std::uint8_t* p, ByteOrder order) : p_(p), order_(order) {}
  template <class T>
  void number(std::size_t at, T& value) {
    using U = Unsigned<sizeof(T)>;
    const U u = std::bit_cast<U>(value);
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      const std::size_t k = order_ == ByteOrder::kBig ? i : sizeof(T) - 1 - i;
      p_[at + k] = std::uint8_t(u >> (8 * (sizeof(T) - 1 - i)));
    }
  }
  template <class T>
  void bits(std::size_t at, int shift, int width, T& value) {
    const int mask = (1 << width) - 1;
    p_[at] = std::uint8_t((p_[at] & ~(mask << shift)) | ((int(value) & mask) << shift));
  }

 private:
  std::uint8_t* p_;
  ByteOrder order_;
};

// The layouts (CIGI 3.3 ICD, section 4). Bytes 0 and 1 (identifier, size) are the caller's.
template <class C>
void layout(C& c, IgControl& p) {
  std::uint8_t version = kVersion;
  std::uint16_t magic = kMagic;
  c.number(2, version);
  c.number(3, p.database);
  c.bits(4, 0, 2, p.mode);
  c.bits(4, 2, 1, p.timestamp_valid);
  c.bits(4, 3, 1, p.extrapolation);
  c.bits(4, 4, 4, p.minor_version);
  c.number(6, magic);
  c.number(8, p.host_frame);
  c.number(12, p.timestamp);
  c.number(16, p.last_ig_frame);
}

template <class C>
void layout(C& c, StartOfFrame& p) {
  std::uint8_t version = kVersion;
  std::uint16_t magic = kMagic;
  c.number(2, version);
  c.number(3, p.database);
  c.number(4, p.ig_status);
  c.bits(5, 0, 2, p.mode);
  c.bits(5, 2, 1, p.timestamp_valid);
  c.bits(5, 3, 1, p.host_earth_model);
  c.bits(5, 4, 4, p.minor_version);
  c.number(6, magic);
  c.number(8, p.ig_frame);
  c.number(12, p.timestamp);
  c.number(16, p.last_host_frame);
}

template <class C>
void layout(C& c, EntityControl& p) {
  c.number(2, p.entity_id);
  c.bits(4, 0, 2, p.state);
  c.bits(4, 2, 1, p.attached);
  c.bits(4, 3, 1, p.collision_detection);
  c.bits(4, 4, 1, p.inherit_alpha);
  c.bits(4, 5, 2, p.clamp);
  c.number(6, p.alpha);
  c.number(8, p.type);
  c.number(10, p.parent_id);
  c.number(12, p.roll);
  c.number(16, p.pitch);
  c.number(20, p.yaw);
  c.number(24, p.latitude);
  c.number(32, p.longitude);
  c.number(40, p.altitude);
}

template <class C>
void layout(C& c, ViewControl& p) {
  c.number(2, p.view_id);
  c.number(4, p.group_id);
  c.bits(5, 0, 6, p.enables);
  c.number(6, p.entity_id);
  c.number(8, p.x);
  c.number(12, p.y);
  c.number(16, p.z);
  c.number(20, p.roll);
  c.number(24, p.pitch);
  c.number(28, p.yaw);
}

template <class C>
void layout(C& c, ViewDefinition& p) {
  c.number(2, p.view_id);
  c.number(4, p.group_id);
  c.bits(5, 0, 6, p.enables);
  c.bits(5, 6, 2, p.mirror_mode);
  c.bits(6, 0, 3, p.pixel_replication);
  c.bits(6, 3, 1, p.orthographic);
  c.bits(6, 4, 1, p.reorder);
  c.bits(6, 5, 3, p.view_type);
  c.number(8, p.near_m);
  c.number(12, p.far_m);
  c.number(16, p.left);
  c.number(20, p.right);
  c.number(24, p.top);
  c.number(28, p.bottom);
}

template <class C>
void layout(C& c, WeatherControl& p) {
  c.number(2, p.entity_region_id);
  c.number(4, p.layer);
  c.number(5, p.humidity);
  c.bits(6, 0, 1, p.enabled);
  c.bits(6, 1, 1, p.scud);
  c.bits(6, 2, 1, p.random_winds);
  c.bits(6, 3, 1, p.random_lightning);
  c.bits(6, 4, 4, p.cloud_type);
  c.bits(7, 0, 2, p.scope);
  c.bits(7, 2, 3, p.severity);
  float* floats[] = {&p.air_temperature, &p.visibility, &p.scud_frequency,
                     &p.coverage,        &p.base,       &p.thickness,
                     &p.transition_band, &p.wind_speed, &p.vertical_wind,
                     &p.wind_direction,  &p.pressure,   &p.aerosol};
  for (std::size_t i = 0; i < std::size(floats); ++i) c.number(8 + 4 * i, *floats[i]);
}

template <class C>
void layout(C& c, EnvironmentalRegionControl& p) {
  c.number(2, p.region_id);
  c.bits(4, 0, 2, p.state);
  c.bits(4, 2, 1, p.merge_weather);
  c.bits(4, 3, 1, p.merge_aerosol);
  c.bits(4, 4, 1, p.merge_maritime);
  c.bits(4, 5, 1, p.merge_terrestrial);
  c.number(8, p.latitude);
  c.number(16, p.longitude);
  c.number(24, p.size_x);
  c.number(28, p.size_y);
  c.number(32, p.corner_radius);
  c.number(36, p.rotation);
  c.number(40, p.transition_perimeter);
}

template <class C>
void layout(C& c, AtmosphereControl& p) {
  c.bits(2, 0, 1, p.model_enabled);
  c.number(3, p.humidity);
  c.number(4, p.air_temperature);
  c.number(8, p.visibility);
  c.number(12, p.wind_speed);
  c.number(16, p.vertical_wind);
  c.number(20, p.wind_direction);
  c.number(24, p.pressure);
}

template <class C>
void layout(C& c, MaritimeSurfaceConditionsControl& p) {
  c.number(2, p.entity_region_id);
  c.bits(4, 0, 1, p.surface_conditions_enabled);
  c.bits(4, 1, 1, p.whitecaps);
  c.bits(4, 2, 2, p.scope);
  c.number(8, p.sea_surface_height);
  c.number(12, p.water_temperature);
  c.number(16, p.clarity);
}

template <class C>
void layout(C& c, WaveControl& p) {
  c.number(2, p.entity_region_id);
  c.number(4, p.wave_id);
  c.bits(5, 0, 1, p.enabled);
  c.bits(5, 1, 2, p.scope);
  c.bits(5, 3, 2, p.breaker);
  c.number(8, p.height);
  c.number(12, p.wavelength);
  c.number(16, p.period);
  c.number(20, p.direction);
  c.number(24, p.phase_offset);
  c.number(28, p.leading);
}

template <class C>
void layout(C& c, CelestialSphereControl& p) {
  c.number(2, p.hour);
  c.number(3, p.minute);
  c.bits(4, 0, 1, p.ephemeris);
  c.bits(4, 1, 1, p.sun);
  c.bits(4, 2, 1, p.moon);
  c.bits(4, 3, 1, p.stars);
  c.bits(4, 4, 1, p.date_valid);
  c.number(8, p.date);
  c.number(12, p.star_intensity);
}

// Identifier, size and name of each packet type Nephele reads or writes.
struct Kind {
  std::uint8_t id, size;
  const char* name;
};
constexpr Kind kindOf(const IgControl&) {
  return {Id::kIgControl, Size::kIgControl, "IG Control"};
}
constexpr Kind kindOf(const StartOfFrame&) {
  return {Id::kStartOfFrame, Size::kStartOfFrame, "Start of Frame"};
}
constexpr Kind kindOf(const EntityControl&) {
  return {Id::kEntityControl, Size::kEntityControl, "Entity Control"};
}
constexpr Kind kindOf(const ViewControl&) {
  return {Id::kViewControl, Size::kViewControl, "View Control"};
}
constexpr Kind kindOf(const ViewDefinition&) {
  return {Id::kViewDefinition, Size::kViewDefinition, "View Definition"};
}
constexpr Kind kindOf(const WeatherControl&) {
  return {Id::kWeatherControl, Size::kWeatherControl, "Weather Control"};
}
constexpr Kind kindOf(const EnvironmentalRegionControl&) {
  return {Id::kEnvironmentalRegionControl, Size::kEnvironmentalRegionControl,
          "Environmental Region Control"};
}
constexpr Kind kindOf(const AtmosphereControl&) {
  return {Id::kAtmosphereControl, Size::kAtmosphereControl, "Atmosphere Control"};
}
constexpr Kind kindOf(const MaritimeSurfaceConditionsControl&) {
  return {Id::kMaritimeSurfaceConditionsControl, Size::kMaritimeSurfaceConditionsControl,
          "Maritime Surface Conditions Control"};
}
constexpr Kind kindOf(const WaveControl&) {
  return {Id::kWaveControl, Size::kWaveControl, "Wave Control"};
}
constexpr Kind kindOf(const CelestialSphereControl&) {
  return {Id::kCelestialSphereControl, Size::kCelestialSphereControl, "Celestial Sphere Control"};
}

// The packet types decoded into fields; any other is kept as an OtherPacket.
template <class... T>
struct PacketTypes {};
using Decoded = PacketTypes<IgControl, StartOfFrame, EntityControl, ViewControl, ViewDefinition,
                            WeatherControl, EnvironmentalRegionControl, AtmosphereControl,
                            CelestialSphereControl, MaritimeSurfaceConditionsControl, WaveControl>;

template <class T>
Packet read(const std::uint8_t* p, ByteOrder order) {
  T packet;
  Reader r(p, order);
  layout(r, packet);
  return packet;
}

std::string number(std::size_t n) {
  return std::to_string(n);
}

// Decodes a message whose first packet must be `first` (IG Control or Start of Frame).
std::variant<Message, DecodeError> decode(std::span<const std::uint8_t> bytes, Kind first) {
  if (bytes.size() > kMaxMessageBytes)
    return DecodeError{Fault::kOversized, "message of " + number(bytes.size()) +
                                              " bytes (allowed: at most " +
                                              number(kMaxMessageBytes) + ")"};
  if (bytes.size() < first.size)
    return DecodeError{Fault::kTruncated, "message of " + number(bytes.size()) +
                                              " bytes is shorter than a " + first.name +
                                              " packet (" + number(first.size) + " bytes)"};
  if (bytes[0] != first.id || bytes[1] != first.size)
    return DecodeError{Fault::kWrongFirst, std::string("the first packet must be ") + first.name +
                                               " (identifier " + number(first.id) + ", size " +
                                               number(first.size) + "); it has identifier " +
                                               number(bytes[0]) + " and size " + number(bytes[1])};
  if (bytes[2] != kVersion)
    return DecodeError{Fault::kVersion, "CIGI version " + number(bytes[2]) +
                                            " (allowed: 3; Nephele speaks CIGI 3.3)"};
  // The magic number is written in the sender's order: 0x80 0x00 big-endian, 0x00 0x80 little.
  Message message;
  if (bytes[6] == 0x80 && bytes[7] == 0x00)
    message.order = ByteOrder::kBig;
  else if (bytes[6] == 0x00 && bytes[7] == 0x80)
    message.order = ByteOrder::kLittle;
  else
    return DecodeError{Fault::kMagic,
                       "bytes 6-7 of the first packet are not the magic number "
                       "0x8000 in either byte order"};
  for (std::size_t at = 0; at < bytes.size();) {
    if (bytes.size() - at < 2)
      return DecodeError{Fault::kTruncated, "a packet header at byte " + number(at) +
                                                " runs past the end of the message"};
    const std::uint8_t id = bytes[at], size = bytes[at + 1];
    if (size == 0 || size % kPacketAlign != 0)
      return DecodeError{Fault::kMalformed, "packet " + number(id) + " at byte " + number(at) +
                                                " has size " + number(size) +
                                                " (allowed: a non-zero multiple of 8)"};
    if (size > bytes.size() - at)
      return DecodeError{Fault::kTruncated, "packet " + number(id) + " at byte " + number(at) +
                                                " of size " + number(size) +
                                                " runs past the end of the message (" +
                                                number(bytes.size()) + " bytes)"};
    const std::uint8_t* p = bytes.data() + at;
    std::optional<DecodeError> error;
    bool decoded = false;
    auto readAs = [&]<class T>(T) {
      const Kind kind = kindOf(T{});
      if (id != kind.id) return;
      decoded = true;
      const bool opening = id == Id::kIgControl || id == Id::kStartOfFrame;
      if (size != kind.size)
        error = DecodeError{Fault::kMalformed, std::string(kind.name) + " at byte " + number(at) +
                                                   " has size " + number(size) +
                                                   " (allowed: " + number(kind.size) + ")"};
      else if (opening && (at != 0 || first.id != id))
        error = DecodeError{Fault::kMalformed, std::string(kind.name) + " at byte " + number(at) +
                                                   " (allowed: once, as the first packet of " +
                                                   (id == Id::kIgControl ? "a host" : "an IG") +
                                                   " message)"};
      else
        message.packets.push_back(read<T>(p, message.order));
    };
    [&]<class... T>(PacketTypes<T...>) { (readAs(T{}), ...); }(Decoded{});
    if (!decoded) message.packets.push_back(OtherPacket{id, size});
    if (error) return *error;
    at += size;
  }
  return message;
}

}  // namespace

std::string_view faultName(Fault fault) {
  switch (fault) {
    case Fault::kTruncated:
      return "truncated";
    case Fault::kOversized:
      return "oversized";
    case Fault::kMalformed:
      return "malformed";
    case Fault::kWrongFirst:
      return "wrong_first_packet";
    case Fault::kVersion:
      return "wrong_version";
    case Fault::kMagic:
      return "bad_magic";
  }
  return "malformed";
}

std::variant<Message, DecodeError> decodeHostMessage(std::span<const std::uint8_t> bytes) {
  return decode(bytes, kindOf(IgControl{}));
}

std::variant<Message, DecodeError> decodeIgMessage(std::span<const std::uint8_t> bytes) {
  return decode(bytes, kindOf(StartOfFrame{}));
}

void encode(const Packet& packet, ByteOrder order, std::vector<std::uint8_t>& out) {
  std::visit(
      [&](const auto& typed) {
        using T = std::decay_t<decltype(typed)>;
        if constexpr (std::is_same_v<T, OtherPacket>) {
          const std::size_t at = out.size();
          out.resize(at + typed.size, 0);
          out[at] = typed.id;
          out[at + 1] = typed.size;
        } else {
          const Kind kind = kindOf(typed);
          const std::size_t at = out.size();
          out.resize(at + kind.size, 0);  // reserved bytes and bits are zero
          out[at] = kind.id;
          out[at + 1] = kind.size;
          T copy = typed;
          Writer w(out.data() + at, order);
          layout(w, copy);
        }
      },
      packet);
}

}  // namespace nephele::cigi
