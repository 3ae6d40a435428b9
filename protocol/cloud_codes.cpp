#include "protocol/cloud_codes.h"

#include <array>

namespace nephele {
namespace {

// Indexed by host code (CIGI 3.3 ICD, Weather Control, Cloud Type).
constexpr std::array<CloudType, kCloudTypeCodes> kByCode{
    CloudType::kNone,          CloudType::kAltocumulus,  CloudType::kAltostratus,
    CloudType::kCirrocumulus,  CloudType::kCirrostratus, CloudType::kCirrus,
    CloudType::kCumulonimbus,  CloudType::kCumulus,      CloudType::kNimbostratus,
    CloudType::kStratocumulus, CloudType::kStratus,
};

}  // namespace

std::optional<CloudType> cloudTypeFromCode(int code) {
  if (code < 0 || code >= int(kByCode.size())) return std::nullopt;
  return kByCode[std::size_t(code)];
}

int cloudTypeCode(CloudType type) {
  for (std::size_t code = 0; code < kByCode.size(); ++code)
    if (kByCode[code] == type) return int(code);
  return 0;  // every genus has a code (tests/messages_test.cpp checks it)
}

std::string cloudTypeCodesAllowed() {
  return "0 to " + std::to_string(kByCode.size() - 1);
}

std::string cloudTypeCodesListed() {
  std::string out;
  for (std::size_t code = 0; code < kByCode.size(); ++code)
    out +=
        (code ? ", " : "") + std::to_string(code) + " " + std::string(cloudTypeName(kByCode[code]));
  return out;
}

}  // namespace nephele
