#pragma once
// The Modbus TCP register map (protocol/MODBUS.md): holding registers, coils and input
// registers to typed values and commands, and back. No sockets.
//
// A float32 takes two registers, high word first (big-endian word order, "ABCD"): register
// n holds bits 31..16 and register n+1 bits 15..0. Addresses here are 0-based protocol
// addresses (a 4xxxx-style reference adds 40001).
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "protocol/messages.h"
#include "protocol/modbus_adu.h"

namespace nephele {

struct ModbusMap {
  // Holding registers (read 0x03; write 0x06, 0x10).
  static constexpr int kPositionX = 0, kPositionY = 2, kPositionZ = 4;    // float32 m
  static constexpr int kHeading = 6, kPitch = 8, kRoll = 10, kVfov = 12;  // float32 degrees
  static constexpr int kWidth = 14, kHeight = 15;                         // uint16 pixels
  static constexpr int kWindEast = 16, kWindNorth = 18;                   // float32 m/s
  static constexpr int kSunAzimuth = 20, kSunElevation = 22;              // float32 degrees
  static constexpr int kTimeScale = 24;                                   // float32
  static constexpr int kHazeVisibility = 26;                              // float32 m; 0: no haze
  static constexpr int kHazeScaleHeight = 28;                             // float32 m
  // Weather layers 1..3 at kLayerStart + (layer - 1) * kLayerStride.
  static constexpr int kLayerStart = 32, kLayerStride = 8;
  static constexpr int kLayerType = 0;       // uint16, CIGI cloud type 0..10
  static constexpr int kLayerBase = 1;       // float32 m
  static constexpr int kLayerThickness = 3;  // float32 m
  static constexpr int kLayerCoverage = 5;   // float32 percent
  // Atmosphere after the layers: ground fog, and the sun from a date and time at [site].
  static constexpr int kFogTop = 56;         // float32 m
  static constexpr int kFogVisibility = 58;  // float32 m; 0: no fog
  static constexpr int kSunDate = 60;        // uint32 YYYYMMDD, high word first; 0: by angles
  static constexpr int kSunTime = 62;        // float32 seconds into the UTC day
  static constexpr int kFogColour = 64;      // 3 x float32, linear RGB
  static constexpr int kHoldingCount = 70;

  // Coils (read 0x01; write 0x05, 0x0F).
  static constexpr int kRenderCoil = 0;  // write 1: render the Modbus view; reads 0 when done
  static constexpr int kPauseCoil = 1;   // 1: simulation time stands still
  static constexpr int kCoilCount = 2;

  // Input registers (read 0x04).
  static constexpr int kStatus = 0;     // uint16, RunState
  static constexpr int kFrames = 1;     // uint32, frames rendered
  static constexpr int kRenderMs = 3;   // float32, last render's milliseconds
  static constexpr int kTicks = 5;      // uint64 in four registers, most significant first
  static constexpr int kLastError = 9;  // uint16, 0 or 1 + the ErrorCode of the last error
  static constexpr int kTime = 10;      // float32, simulation seconds
  static constexpr int kInputCount = 12;
};

using HoldingRegisters = std::array<std::uint16_t, ModbusMap::kHoldingCount>;
using InputRegisters = std::array<std::uint16_t, ModbusMap::kInputCount>;

HoldingRegisters encodeHolding(const HostReadings& settings);
InputRegisters encodeInput(const HostStatus& status);

struct RegisterError {
  int exception = kIllegalDataValue;
  std::string message;
};

// A write of `values` at `address` over the current registers: the commands it amounts to
// (view changes go to `view`), or the exception to answer. Never throws.
std::variant<std::vector<Command>, RegisterError> decodeHoldingWrite(
    const HoldingRegisters& current, int address, std::span<const std::uint16_t> values,
    const std::string& view);

struct CoilWrite {
  bool render = false;         // the render coil was set to 1
  std::optional<bool> paused;  // the pause coil was written
};
std::variant<CoilWrite, RegisterError> decodeCoilWrite(int address,
                                                       std::span<const std::uint8_t> bits);

// Float32 in two registers, high word first.
void putFloat(std::uint16_t* registers, double value);
float getFloat(const std::uint16_t* registers);

}  // namespace nephele
