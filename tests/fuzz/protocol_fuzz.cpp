// libFuzzer target for the bytes the daemon takes from the network: socket-protocol request
// lines (with the cloud and target objects of add_cloud and add_target, which the world thread
// reads through the scene-file readers), Modbus TCP frames, Modbus register and coil writes,
// and CIGI datagrams. Built with clang
// by tests/CMakeLists.txt and run briefly by ctest. The first input byte picks the decoder.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "config/scene_file.h"
#include "protocol/cigi.h"
#include "protocol/cigi_session.h"
#include "protocol/messages.h"
#include "protocol/modbus_adu.h"
#include "protocol/register_map.h"
#include "tests/fuzz/world_work.h"
#include "world/formations/weather.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace nephele;
  if (size < 1) return 0;
  const std::uint8_t selector = data[0];
  ++data, --size;
  if (selector >= 0xF0) {
    // A CIGI host datagram: decoded, mapped to commands by a session, and every decoded
    // packet written again must read back the same.
    const auto decoded = cigi::decodeHostMessage(std::span(data, size));
    if (const auto* m = std::get_if<cigi::Message>(&decoded)) {
      std::vector<std::uint8_t> again;
      for (const cigi::Packet& p : m->packets) cigi::encode(p, m->order, again);
      const auto redecoded = cigi::decodeHostMessage(again);
      const auto* m2 = std::get_if<cigi::Message>(&redecoded);
      if (!m2 || m2->packets.size() != m->packets.size()) __builtin_trap();
      for (std::size_t i = 0; i < m->packets.size(); ++i) {
        const cigi::Packet& a = m->packets[i];
        const bool comparable = a == a;  // a NaN field compares unequal to itself
        if (comparable && !(a == m2->packets[i])) __builtin_trap();
      }
      cigi::SessionSettings settings;
      settings.views = {"front", "left"};
      settings.entity_types = {{1001, "rib"}};
      cigi::Session session(settings);
      (void)session.map(*m);
      session.commit();
      (void)session.map(*m);
    }
    return 0;
  }
  if (selector % 4 == 3) {
    // A stream of Modbus TCP frames, framed the way the server frames them.
    while (size >= ModbusAdu::kHeaderBytes) {
      auto header = decodeMbapHeader(
          std::span<const std::uint8_t, ModbusAdu::kHeaderBytes>(data, ModbusAdu::kHeaderBytes));
      if (std::holds_alternative<std::string>(header)) return 0;  // the server closes
      const MbapHeader& h = std::get<MbapHeader>(header);
      if (size < ModbusAdu::kHeaderBytes + h.pduBytes()) return 0;
      const auto request =
          decodeModbusPdu(h, std::span(data + ModbusAdu::kHeaderBytes, h.pduBytes()));
      std::vector<std::uint8_t> reply;
      if (const auto* r = std::get_if<ModbusRequest>(&request)) {
        const std::vector<std::uint16_t> registers(std::size_t(r->count), 0x1234);
        const std::vector<std::uint8_t> bits(std::size_t(r->count), 1);
        reply = r->function == ModbusFunction::kReadHoldingRegisters ||
                        r->function == ModbusFunction::kReadInputRegisters
                    ? encodeReadRegisters(*r, registers)
                : r->function == ModbusFunction::kReadCoils ||
                        r->function == ModbusFunction::kReadDiscreteInputs
                    ? encodeReadBits(*r, bits)
                    : encodeWriteReply(*r);
      } else {
        reply = encodeModbusException(h, std::get<ModbusException>(request));
      }
      // Every reply is one well-formed ADU no longer than the protocol allows.
      if (reply.size() < ModbusAdu::kHeaderBytes + 2 || reply.size() > ModbusAdu::kMaxAduBytes)
        __builtin_trap();
      data += ModbusAdu::kHeaderBytes + h.pduBytes();
      size -= ModbusAdu::kHeaderBytes + h.pduBytes();
    }
    return 0;
  }
  if (selector % 3 == 0) {
    const auto result = parseRequest(std::string_view(reinterpret_cast<const char*>(data), size));
    // Every outcome must turn into a reply line.
    if (const auto* bad = std::get_if<BadRequest>(&result)) {
      (void)errorReply(bad->id, bad->error);
      return 0;
    }
    const Command& command = std::get<Request>(result).command;
    (void)okReply(std::get<Request>(result).id, commandName(command));
    // The objects the world thread reads later, through the scene-file readers, and what it
    // then does with a cloud or a weather layer (world_work.h).
    if (const auto* c = std::get_if<command::AddCloud>(&command)) {
      EllipsoidCloud cloud;
      if (!parseCloudJson(c->cloud, 1, cloud).empty()) return 0;
      Scene scene;
      scene.clouds.push_back(std::move(cloud));
      exerciseWorld(scene, {});
    } else if (const auto* w = std::get_if<command::SetWeather>(&command)) {
      WeatherClouds drawn = weatherClouds(w->weather, "weather/1", weatherSeed(1, w->layer));
      Scene scene;
      scene.layers = std::move(drawn.layers);
      scene.fields = std::move(drawn.fields);
      exerciseWorld(scene, {});
    } else if (const auto* c = std::get_if<command::SetSea>(&command)) {
      // Every sea a request can ask for is one the world holds (the one table of ranges).
      Sea sea;
      sea.fetch_m = c->fetch.value_or(sea.fetch_m);
      sea.temperature_c = c->temperature.value_or(sea.temperature_c);
      sea.clarity = c->clarity.value_or(sea.clarity);
      sea.seed = c->seed.value_or(sea.seed);
      for (const command::WavePatch& w : c->waves) {
        WaveTrain& t = sea.trains.emplace_back();
        t.id = w.id;
        t.height_m = w.height.value_or(t.height_m);
        t.wavelength_m = w.wavelength.value_or(t.wavelength_m);
        t.period_s = w.period.value_or(t.period_s);
        t.direction_deg = w.direction.value_or(t.direction_deg);
        t.phase_deg = w.phase.value_or(t.phase_deg);
      }
      if (!seaError(sea).empty()) __builtin_trap();
      Scene scene;
      scene.sea = sea;
      exerciseWorld(scene, {});
    } else if (const auto* t = std::get_if<command::AddTarget>(&command)) {
      Target target;
      (void)parseTargetJson(t->target, {}, target);
    }
    return 0;
  }
  if (size < 2) return 0;
  const int address = int(data[0]) | int(data[1] & 0x7f) << 8;
  data += 2, size -= 2;
  if (selector % 3 == 1) {
    std::vector<std::uint16_t> values;
    for (std::size_t i = 0; i + 1 < size && values.size() < 123; i += 2)
      values.push_back(std::uint16_t(data[i] << 8 | data[i + 1]));
    HostReadings settings;
    (void)decodeHoldingWrite(encodeHolding(settings), address - 64, values, "front");
  } else {
    std::vector<std::uint8_t> bits(data, data + std::min<std::size_t>(size, 1968));
    (void)decodeCoilWrite(address - 8, bits);
  }
  return 0;
}
