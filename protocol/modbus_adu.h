#pragma once
// Modbus TCP framing and PDUs (protocol/MODBUS.md): bytes to typed requests and replies to
// bytes, following the Modbus Application Protocol Specification v1.1b3 (function codes,
// quantities, exception codes) and the Modbus Messaging on TCP/IP Implementation Guide
// v1.0b (the MBAP header). No sockets: the server reads exactly what the header says.
//
// An ADU is the 7-byte MBAP header (transaction id, protocol id = 0, length, unit id; each
// 16-bit field big-endian) followed by the PDU (function code and data). `length` counts the
// unit id and the PDU, so the PDU is length - 1 bytes.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <variant>
#include <vector>

namespace nephele {

// The sizes of an ADU (Implementation Guide section 3.1.3) and the quantities of its PDU.
struct ModbusAdu {
  static constexpr std::size_t kHeaderBytes = 7;
  static constexpr std::size_t kMaxAduBytes = 260;
  static constexpr int kMinLength = 2;    // unit id and a function code
  static constexpr int kMaxLength = 254;  // kMaxAduBytes - 6
  // Quantities one request may carry (Application Protocol sections 6.1 to 6.12).
  static constexpr int kMaxReadBits = 2000, kMaxReadRegisters = 125;
  static constexpr int kMaxWriteBits = 1968, kMaxWriteRegisters = 123;
};

enum class ModbusFunction : std::uint8_t {
  kReadCoils = 0x01,
  kReadDiscreteInputs = 0x02,
  kReadHoldingRegisters = 0x03,
  kReadInputRegisters = 0x04,
  kWriteSingleCoil = 0x05,
  kWriteSingleRegister = 0x06,
  kWriteMultipleCoils = 0x0F,
  kWriteMultipleRegisters = 0x10,
};

// Exception codes (Application Protocol section 7).
inline constexpr int kIllegalFunction = 0x01;
inline constexpr int kIllegalDataAddress = 0x02;
inline constexpr int kIllegalDataValue = 0x03;
inline constexpr int kServerDeviceBusy = 0x06;

struct MbapHeader {
  std::uint16_t transaction = 0;
  std::uint16_t protocol = 0;
  std::uint16_t length = 0;
  std::uint8_t unit = 0;
  std::size_t pduBytes() const { return std::size_t(length) - 1; }
};

// The header at the start of a stream, or why the stream cannot be framed (a protocol id
// other than 0 or a length outside 2..254): then nothing after it can be trusted and the
// connection must close.
std::variant<MbapHeader, std::string> decodeMbapHeader(
    std::span<const std::uint8_t, ModbusAdu::kHeaderBytes> bytes);

struct ModbusRequest {
  MbapHeader header;
  ModbusFunction function{};
  int address = 0;
  int count = 0;                         // registers or bits read or written
  std::vector<std::uint16_t> registers;  // written registers
  std::vector<std::uint8_t> bits;        // written coils, one per entry (0 or 1)
};

struct ModbusException {
  std::uint8_t function = 0;  // the request's function code
  int code = kIllegalFunction;
  std::string message;
};

// One PDU (exactly header.pduBytes() bytes). A PDU whose size is not what its function and
// quantities require (trailing bytes included) is refused with kIllegalDataValue, any
// function this server does not implement (including codes of 0x80 and above) with
// kIllegalFunction. Never throws.
std::variant<ModbusRequest, ModbusException> decodeModbusPdu(const MbapHeader& header,
                                                             std::span<const std::uint8_t> pdu);

// Replies, each a whole ADU echoing the request's transaction and unit ids.
std::vector<std::uint8_t> encodeModbusException(const MbapHeader& header,
                                                const ModbusException& exception);
// Reads of coils (one value per entry, 0 or 1) and of registers.
std::vector<std::uint8_t> encodeReadBits(const ModbusRequest& request,
                                         std::span<const std::uint8_t> bits);
std::vector<std::uint8_t> encodeReadRegisters(const ModbusRequest& request,
                                              std::span<const std::uint16_t> registers);
// The reply to a write that was applied.
std::vector<std::uint8_t> encodeWriteReply(const ModbusRequest& request);

}  // namespace nephele
