#include "protocol/modbus_adu.h"

#include <optional>

namespace nephele {
namespace {

std::uint16_t be16(const std::uint8_t* p) {
  return std::uint16_t(p[0] << 8 | p[1]);
}

void put16(std::vector<std::uint8_t>& out, int value) {
  out.push_back(std::uint8_t(value >> 8));
  out.push_back(std::uint8_t(value));
}

// The MBAP header of a reply whose PDU is `pdu_bytes` long; the PDU is appended after it.
std::vector<std::uint8_t> replyHeader(const MbapHeader& request, std::size_t pdu_bytes) {
  std::vector<std::uint8_t> out;
  out.reserve(ModbusAdu::kHeaderBytes + pdu_bytes);
  put16(out, request.transaction);
  put16(out, 0);
  put16(out, int(pdu_bytes + 1));
  out.push_back(request.unit);
  return out;
}

ModbusException refuse(std::uint8_t function, int code, std::string message) {
  return {function, code, std::move(message)};
}

// A PDU of `pdu.size()` bytes where its function takes `expected`.
ModbusException wrongSize(std::span<const std::uint8_t> pdu, std::size_t expected) {
  return refuse(pdu[0], kIllegalDataValue,
                "function " + std::to_string(pdu[0]) + " takes " + std::to_string(expected) +
                    " PDU bytes, the frame holds " + std::to_string(pdu.size()));
}

// What is wrong with a request's quantity (1 to `max`) and the addresses it spans, or none.
std::optional<ModbusException> quantityError(const ModbusRequest& r, std::uint8_t code, int max) {
  if (r.count < 1 || r.count > max)
    return refuse(code, kIllegalDataValue,
                  "quantity " + std::to_string(r.count) + " is out of range (allowed: 1 to " +
                      std::to_string(max) + ")");
  return std::nullopt;
}
std::optional<ModbusException> spanError(const ModbusRequest& r, std::uint8_t code) {
  if (r.address + r.count <= 0x10000) return std::nullopt;
  return refuse(code, kIllegalDataAddress, "address + quantity passes 65535");
}

// Read Coils, Discrete Inputs, Holding or Input Registers (Application Protocol sections 6.1
// to 6.4): an address and a quantity.
std::variant<ModbusRequest, ModbusException> decodeRead(ModbusRequest r,
                                                        std::span<const std::uint8_t> pdu) {
  const std::uint8_t code = pdu[0];
  if (pdu.size() != 5) return wrongSize(pdu, 5);
  r.address = be16(&pdu[1]);
  r.count = be16(&pdu[3]);
  const bool bits = code <= 0x02;
  if (auto e =
          quantityError(r, code, bits ? ModbusAdu::kMaxReadBits : ModbusAdu::kMaxReadRegisters))
    return *e;
  if (auto e = spanError(r, code)) return *e;
  return r;
}

// Write Single Coil or Register (sections 6.5 and 6.6): an address and a value; a coil's is
// 0xFF00 or 0x0000.
std::variant<ModbusRequest, ModbusException> decodeWriteSingle(ModbusRequest r,
                                                               std::span<const std::uint8_t> pdu) {
  if (pdu.size() != 5) return wrongSize(pdu, 5);
  r.address = be16(&pdu[1]);
  r.count = 1;
  const std::uint16_t value = be16(&pdu[3]);
  if (r.function == ModbusFunction::kWriteSingleRegister) {
    r.registers.push_back(value);
    return r;
  }
  if (value != 0xFF00 && value != 0x0000)
    return refuse(pdu[0], kIllegalDataValue, "a coil takes 0xFF00 (on) or 0x0000 (off)");
  r.bits.push_back(value == 0xFF00);
  return r;
}

// Write Multiple Coils or Registers (sections 6.11 and 6.12): an address, a quantity, a byte
// count that matches it, and the values (coils packed eight to a byte, low bit first).
std::variant<ModbusRequest, ModbusException> decodeWriteMultiple(
    ModbusRequest r, std::span<const std::uint8_t> pdu) {
  const std::uint8_t code = pdu[0];
  if (pdu.size() < 6) return wrongSize(pdu, 6);
  r.address = be16(&pdu[1]);
  r.count = be16(&pdu[3]);
  const std::size_t bytes = pdu[5];
  const bool coils = r.function == ModbusFunction::kWriteMultipleCoils;
  if (auto e =
          quantityError(r, code, coils ? ModbusAdu::kMaxWriteBits : ModbusAdu::kMaxWriteRegisters))
    return *e;
  const std::size_t needed = coils ? std::size_t(r.count + 7) / 8 : std::size_t(r.count) * 2;
  if (bytes != needed)
    return refuse(code, kIllegalDataValue,
                  "byte count " + std::to_string(bytes) + " does not match quantity " +
                      std::to_string(r.count) + " (allowed: " + std::to_string(needed) + ")");
  if (pdu.size() != 6 + bytes) return wrongSize(pdu, 6 + bytes);
  if (auto e = spanError(r, code)) return *e;
  const std::uint8_t* data = &pdu[6];
  for (int i = 0; i < r.count; ++i) {
    if (coils)
      r.bits.push_back((data[i / 8] >> (i % 8)) & 1);
    else
      r.registers.push_back(be16(data + 2 * i));
  }
  return r;
}

}  // namespace

std::variant<MbapHeader, std::string> decodeMbapHeader(
    std::span<const std::uint8_t, ModbusAdu::kHeaderBytes> bytes) {
  MbapHeader h;
  h.transaction = be16(&bytes[0]);
  h.protocol = be16(&bytes[2]);
  h.length = be16(&bytes[4]);
  h.unit = bytes[6];
  if (h.protocol != 0)
    return "protocol id " + std::to_string(h.protocol) + " is not Modbus (allowed: 0)";
  if (h.length < ModbusAdu::kMinLength || h.length > ModbusAdu::kMaxLength)
    return "length " + std::to_string(h.length) +
           " is out of range (allowed: " + std::to_string(ModbusAdu::kMinLength) + " to " +
           std::to_string(ModbusAdu::kMaxLength) + ")";
  return h;
}

std::variant<ModbusRequest, ModbusException> decodeModbusPdu(const MbapHeader& header,
                                                             std::span<const std::uint8_t> pdu) {
  if (pdu.empty()) return refuse(0, kIllegalFunction, "no function code");
  const std::uint8_t code = pdu[0];
  ModbusRequest r;
  r.header = header;
  r.function = ModbusFunction(code);
  switch (r.function) {
    case ModbusFunction::kReadCoils:
    case ModbusFunction::kReadDiscreteInputs:
    case ModbusFunction::kReadHoldingRegisters:
    case ModbusFunction::kReadInputRegisters:
      return decodeRead(std::move(r), pdu);
    case ModbusFunction::kWriteSingleCoil:
    case ModbusFunction::kWriteSingleRegister:
      return decodeWriteSingle(std::move(r), pdu);
    case ModbusFunction::kWriteMultipleCoils:
    case ModbusFunction::kWriteMultipleRegisters:
      return decodeWriteMultiple(std::move(r), pdu);
  }
  return refuse(
      code, kIllegalFunction,
      "function " + std::to_string(code) + " is not served (allowed: 1, 2, 3, 4, 5, 6, 15, 16)");
}

std::vector<std::uint8_t> encodeModbusException(const MbapHeader& header,
                                                const ModbusException& exception) {
  std::vector<std::uint8_t> out = replyHeader(header, 2);
  out.push_back(std::uint8_t(exception.function | 0x80));
  out.push_back(std::uint8_t(exception.code));
  return out;
}

std::vector<std::uint8_t> encodeReadBits(const ModbusRequest& request,
                                         std::span<const std::uint8_t> bits) {
  const std::size_t bytes = (bits.size() + 7) / 8;
  std::vector<std::uint8_t> out = replyHeader(request.header, 2 + bytes);
  out.push_back(std::uint8_t(request.function));
  out.push_back(std::uint8_t(bytes));
  const std::size_t first = out.size();
  out.resize(first + bytes, 0);
  for (std::size_t i = 0; i < bits.size(); ++i)
    if (bits[i]) out[first + i / 8] |= std::uint8_t(1u << (i % 8));
  return out;
}

std::vector<std::uint8_t> encodeReadRegisters(const ModbusRequest& request,
                                              std::span<const std::uint16_t> registers) {
  const std::size_t bytes = 2 * registers.size();
  std::vector<std::uint8_t> out = replyHeader(request.header, 2 + bytes);
  out.push_back(std::uint8_t(request.function));
  out.push_back(std::uint8_t(bytes));
  for (std::uint16_t value : registers) put16(out, value);
  return out;
}

std::vector<std::uint8_t> encodeWriteReply(const ModbusRequest& request) {
  std::vector<std::uint8_t> out = replyHeader(request.header, 5);
  out.push_back(std::uint8_t(request.function));
  put16(out, request.address);
  switch (request.function) {
    case ModbusFunction::kWriteSingleCoil:
      put16(out, request.bits.at(0) ? 0xFF00 : 0x0000);
      break;
    case ModbusFunction::kWriteSingleRegister:
      put16(out, request.registers.at(0));
      break;
    default:
      put16(out, request.count);
  }
  return out;
}

}  // namespace nephele
