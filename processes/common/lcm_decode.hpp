#pragma once
// Decoding an LCM message from untrusted bytes. The decode() that lcm-gen 1.3.1 generates is not
// safe on malformed input (both found by tests/fuzz/lcm_messages.cpp):
//  - a string length field of 0 makes it call std::string::assign with length -1, which throws
//    std::length_error (a negative array count does the same through resize);
//  - an array count is used to allocate the array before the buffer is checked, so a 90-byte
//    message claiming 2^31 beams makes the process allocate (and zero) gigabytes.
//  - a string length of INT_MIN overflows (UB) in the length - 1 it computes.
// decodeLcm() turns all three into a rejected message: the string lengths and array counts of the types processes
// consume are checked against the bytes that follow them first, and exceptions are caught.
// Every decode of received or logged bytes goes through here.
#include <climits>
#include <cstddef>
#include <cstdint>
#include <exception>

#include "polarslam/features_t.hpp"
#include "polarslam/grid_map_t.hpp"
#include "polarslam/laser_scan_t.hpp"
#include "polarslam/path_t.hpp"
#include "polarslam/pose_graph_t.hpp"
#include "polarslam/pose_t.hpp"
#include "polarslam/process_status_t.hpp"
#include "polarslam/sonar_targets_t.hpp"

namespace polarslam {

namespace lcm_decode_detail {

constexpr size_t kHashBytes = 8;

/// Reads the big-endian int32 count at `pos` and advances `pos` past it and the `element_bytes`
/// encoded elements it announces; false when the count is negative or they do not fit in `size`.
inline bool skipArray(const uint8_t* data, size_t size, size_t& pos, size_t element_bytes) {
  if (pos > size || size - pos < 4) return false;
  const uint32_t raw = (uint32_t{data[pos]} << 24) | (uint32_t{data[pos + 1]} << 16) |
                       (uint32_t{data[pos + 2]} << 8) | uint32_t{data[pos + 3]};
  const auto count = static_cast<int32_t>(raw);
  pos += 4;
  if (count < 0) return false;
  if (static_cast<size_t>(count) > (size - pos) / element_bytes) return false;
  pos += static_cast<size_t>(count) * element_bytes;
  return true;
}

/// Skips a string at `pos`: int32 length including the NUL (at least 1), then the bytes.
inline bool skipString(const uint8_t* data, size_t size, size_t& pos) {
  const size_t length_at = pos;
  if (!skipArray(data, size, pos, 1)) return false;
  return pos > length_at + 4;  // an empty length (0) is invalid: lcm-gen would assign -1 bytes
}

template <typename T>
size_t encodedBytes() {
  return static_cast<size_t>(T{}.getEncodedSize()) - kHashBytes;  // fixed-size element types
}

}  // namespace lcm_decode_detail

/// True when the string lengths and array counts of the message in `data` fit in its bytes (types without
/// variable-length arrays always pass; decode() checks the rest).
template <typename MsgT>
bool arrayCountsFit(const MsgT&, const uint8_t*, size_t) { return true; }

inline bool arrayCountsFit(const laser_scan_t&, const uint8_t* data, size_t size) {
  size_t pos = lcm_decode_detail::kHashBytes + 2 * 8 + 4 * 8 + 3 * 8;  // utime seq 4 doubles pose[3]
  return lcm_decode_detail::skipArray(data, size, pos, sizeof(float));
}

inline bool arrayCountsFit(const sonar_targets_t&, const uint8_t* data, size_t size) {
  size_t pos = lcm_decode_detail::kHashBytes + 2 * 8 + 4 + 3 * 8 + 2 * 8;  // utime seq id pose[3] 2 doubles
  return lcm_decode_detail::skipArray(data, size, pos, lcm_decode_detail::encodedBytes<sonar_target_t>());
}

inline bool arrayCountsFit(const pose_t&, const uint8_t* data, size_t size) {
  size_t pos = lcm_decode_detail::kHashBytes + 2 * 8;  // utime seq, then the frame string
  return lcm_decode_detail::skipString(data, size, pos);
}

inline bool arrayCountsFit(const features_t&, const uint8_t* data, size_t size) {
  using namespace lcm_decode_detail;
  size_t pos = kHashBytes + 2 * 8;  // utime seq, then the frame string
  if (!skipString(data, size, pos)) return false;
  pos += 3 * 8;  // sensor_pose[3]
  return skipArray(data, size, pos, encodedBytes<line_feature_t>()) &&
         skipArray(data, size, pos, encodedBytes<corner_feature_t>()) &&
         skipArray(data, size, pos, encodedBytes<point_feature_t>());
}

inline bool arrayCountsFit(const grid_map_t&, const uint8_t* data, size_t size) {
  using namespace lcm_decode_detail;
  size_t pos = kHashBytes + 2 * 8;  // utime seq, then the frame string
  if (!skipString(data, size, pos)) return false;
  pos += 8 + 3 * 8 + 4 + 4 + 1 + 4;  // resolution origin[3] width height encoding scans
  return skipString(data, size, pos) && skipArray(data, size, pos, 1);
}

inline bool arrayCountsFit(const path_t&, const uint8_t* data, size_t size) {
  using namespace lcm_decode_detail;
  size_t pos = kHashBytes + 2 * 8;  // utime seq, then the frame string
  if (!skipString(data, size, pos)) return false;
  pos += 8 + 1;  // goal_utime goal_exact
  return skipArray(data, size, pos, 8 + 8 + 8 + 8 + 1);  // pose_utime x y theta source, per pose
}

inline bool arrayCountsFit(const pose_graph_t&, const uint8_t* data, size_t size) {
  using namespace lcm_decode_detail;
  size_t pos = kHashBytes + 2 * 8;  // utime seq, then the frame string
  if (!skipString(data, size, pos)) return false;
  return skipArray(data, size, pos, 8 + 8 + 3 * 8) &&                 // node id, utime, pose[3]
         skipArray(data, size, pos, 8 + 8 + 1 + 1 + 3 * 8 + 9 * 8);  // edge from, to, kind, active, measurement, cov
}

inline bool arrayCountsFit(const process_status_t&, const uint8_t* data, size_t size) {
  using namespace lcm_decode_detail;
  size_t pos = kHashBytes + 8;  // utime, then name and host
  if (!skipString(data, size, pos) || !skipString(data, size, pos)) return false;
  pos += 4;  // pid
  if (!skipString(data, size, pos)) return false;  // state
  pos += 4 + 3 * 8;  // restarts, handled, rejected, dropped
  const size_t count_at = pos;
  if (!skipArray(data, size, pos, 5)) return false;  // a negative count, or more kinds than 5-byte strings fit
  pos = count_at + 4;
  const size_t count = (size_t{data[count_at]} << 24) | (size_t{data[count_at + 1]} << 16) |
                       (size_t{data[count_at + 2]} << 8) | size_t{data[count_at + 3]};
  for (size_t i = 0; i < count; ++i)
    if (!skipString(data, size, pos)) return false;
  return pos <= size && (size - pos) / 8 >= count;  // reject_counts
}

/// Decodes `size` bytes at `data` into `msg`; false when they are not a valid MsgT.
template <typename MsgT>
bool decodeLcm(MsgT& msg, const void* data, size_t size) noexcept {
  if (size > static_cast<size_t>(INT_MAX)) return false;
  if (!arrayCountsFit(msg, static_cast<const uint8_t*>(data), size)) return false;
  try {
    return msg.decode(data, 0, static_cast<int>(size)) >= 0;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace polarslam
