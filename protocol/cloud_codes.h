#pragma once
// The numeric cloud types hosts send. CIGI 3.3 Weather Control numbers them (0 none,
// 1 altocumulus, 2 altostratus, 3 cirrocumulus, 4 cirrostratus, 5 cirrus, 6 cumulonimbus,
// 7 cumulus, 8 nimbostratus, 9 stratocumulus, 10 stratus; 11 to 15 are left to the IG), and
// the socket protocol's set_weather and the Modbus weather registers take the same codes, so a
// host has one numbering over the three. The world knows genera only by its own table
// (world/formations/genus.h); this is the one place their codes live.
#include <optional>
#include <string>

#include "world/formations/cloud_field.h"

namespace nephele {

// Host codes run from 0 to kCloudTypeCodes - 1.
inline constexpr int kCloudTypeCodes = 11;
// The genus with host code `code`, or nullopt for a code no genus has.
std::optional<CloudType> cloudTypeFromCode(int code);
// The host code of `type`.
int cloudTypeCode(CloudType type);
// The codes a host may send, for error messages: "0 to 10".
std::string cloudTypeCodesAllowed();
// Every code with its genus, for error messages: "0 none, 1 altocumulus, ..., 10 stratus".
std::string cloudTypeCodesListed();

}  // namespace nephele
