// libFuzzer target for the bytes the daemon takes from the network: socket-protocol request
// lines and Modbus register and coil writes. Built with clang by tests/CMakeLists.txt and
// run briefly by ctest. The first input byte picks the decoder.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "protocol/messages.h"
#include "protocol/register_map.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace nephele;
  if (size < 1) return 0;
  const std::uint8_t selector = data[0];
  ++data, --size;
  if (selector % 3 == 0) {
    const auto result = parseRequest(std::string_view(reinterpret_cast<const char*>(data), size));
    // Every outcome must turn into a reply line.
    if (const auto* bad = std::get_if<BadRequest>(&result))
      (void)errorReply(bad->id, bad->error);
    else
      (void)okReply(std::get<Request>(result).id, commandName(std::get<Request>(result).command));
    return 0;
  }
  if (size < 2) return 0;
  const int address = int(data[0]) | int(data[1] & 0x7f) << 8;
  data += 2, size -= 2;
  if (selector % 3 == 1) {
    std::vector<std::uint16_t> values;
    for (std::size_t i = 0; i + 1 < size && values.size() < 123; i += 2)
      values.push_back(std::uint16_t(data[i] << 8 | data[i + 1]));
    ModbusSettings settings;
    (void)decodeHoldingWrite(encodeHolding(settings), address - 64, values, "front");
  } else {
    std::vector<std::uint8_t> bits(data, data + std::min<std::size_t>(size, 1968));
    (void)decodeCoilWrite(address - 8, bits);
  }
  return 0;
}
