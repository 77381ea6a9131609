#pragma once
// Identifies which polarslam message type an encoded LCM payload holds, from its fingerprint.
#include <cstddef>
#include <cstdint>
#include <string>

namespace polarslam {

/// "polarslam.laser_scan_t" etc., or "" when the fingerprint is not one of ours.
std::string lcmTypeName(const uint8_t* data, size_t size);

}  // namespace polarslam
