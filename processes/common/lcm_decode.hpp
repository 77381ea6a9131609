#pragma once
// Decoding an LCM message from untrusted bytes. The decode() that lcm-gen 1.3.1 generates is not
// safe on malformed input (all found by tests/fuzz/lcm_messages.cpp):
//  - a string length field of 0 makes it call std::string::assign with length -1, which throws
//    std::length_error (a negative array count does the same through resize);
//  - an array count is used to allocate the array before the buffer is checked, so a 90-byte
//    message claiming 2^31 beams makes the process allocate (and zero) gigabytes;
//  - a string length of INT_MIN overflows (UB) in the length - 1 it computes.
// decodeLcm() turns all three into a rejected message: before decode() runs, the message's layout
// (below, one walk per type) is checked against its bytes — every string length and array count
// must fit in the bytes that follow, and the walk must end exactly at the message's last byte.
// There is no default walk: decoding a type that has none does not compile, so a new message type
// cannot slip past the check. Every decode of received or logged bytes goes through here.
#include <climits>
#include <cstddef>
#include <cstdint>
#include <exception>

#include "polarslam/anchored_pose_t.hpp"
#include "polarslam/features_t.hpp"
#include "polarslam/goal_t.hpp"
#include "polarslam/grid_map_t.hpp"
#include "polarslam/grid_request_t.hpp"
#include "polarslam/grid_status_t.hpp"
#include "polarslam/laser_scan_t.hpp"
#include "polarslam/map_request_t.hpp"
#include "polarslam/odometry_t.hpp"
#include "polarslam/path_t.hpp"
#include "polarslam/pose_graph_t.hpp"
#include "polarslam/pose_t.hpp"
#include "polarslam/process_status_t.hpp"
#include "polarslam/scan_anchors_t.hpp"
#include "polarslam/scan_match_t.hpp"
#include "polarslam/slam_map_t.hpp"
#include "polarslam/sonar_targets_t.hpp"

namespace polarslam {

/// Walks the encoding of one LCM message (after its 8-byte type hash) field by field, checking each
/// string length and array count against the bytes left. Once a step fails, every later step is a
/// no-op and fits() is false.
class LcmLayout {
 public:
  static constexpr size_t kHashBytes = 8;

  LcmLayout(const uint8_t* data, size_t size) : data_(data), size_(size), pos_(kHashBytes), ok_(size >= kHashBytes) {}

  /// `bytes` of fixed-size fields.
  LcmLayout& fixed(size_t bytes) {
    if (ok_ && size_ - pos_ >= bytes) pos_ += bytes;
    else ok_ = false;
    return *this;
  }

  /// A string: int32 length including the NUL (at least 1), then the bytes.
  LcmLayout& string() {
    const int32_t length = readInt32();
    if (length < 1) ok_ = false;
    return fixed(static_cast<size_t>(length > 0 ? length : 0));
  }

  /// An int32 array count; 0 (and fits() false) when it is negative or the bytes are used up.
  int32_t count() {
    const int32_t n = readInt32();
    if (n < 0) ok_ = false;
    return ok_ ? n : 0;
  }

  /// `count` encoded elements of `element_bytes` each, checked without overflowing.
  LcmLayout& elements(int32_t count, size_t element_bytes) {
    if (!ok_ || count < 0 || static_cast<size_t>(count) > (size_ - pos_) / element_bytes) {
      ok_ = false;
      return *this;
    }
    pos_ += static_cast<size_t>(count) * element_bytes;
    return *this;
  }

  /// An array whose int32 count comes first.
  LcmLayout& array(size_t element_bytes) { return elements(count(), element_bytes); }

  /// A nested pose_t (no hash of its own): utime seq frame x y theta cov[9].
  LcmLayout& pose() { return fixed(2 * 8).string().fixed(12 * 8); }

  bool ok() const { return ok_; }
  bool fits() const { return ok_ && pos_ == size_; }

 private:
  int32_t readInt32() {
    if (!ok_ || size_ - pos_ < 4) {
      ok_ = false;
      return 0;
    }
    const uint32_t raw = (uint32_t{data_[pos_]} << 24) | (uint32_t{data_[pos_ + 1]} << 16) |
                         (uint32_t{data_[pos_ + 2]} << 8) | uint32_t{data_[pos_ + 3]};
    pos_ += 4;
    return static_cast<int32_t>(raw);
  }

  const uint8_t* data_;
  size_t size_;
  size_t pos_;
  bool ok_;
};

/// Encoded bytes of a fixed-size nested type (no hash).
template <typename T>
size_t encodedElementBytes() {
  return static_cast<size_t>(T{}.getEncodedSize()) - LcmLayout::kHashBytes;
}

/// Types without strings or arrays: their size is all there is to check.
template <typename MsgT>
void walkFixed(LcmLayout& at) { at.fixed(encodedElementBytes<MsgT>()); }

inline void walk(const odometry_t&, LcmLayout& at) { walkFixed<odometry_t>(at); }
inline void walk(const anchored_pose_t&, LcmLayout& at) { walkFixed<anchored_pose_t>(at); }
inline void walk(const goal_t&, LcmLayout& at) { walkFixed<goal_t>(at); }
inline void walk(const map_request_t&, LcmLayout& at) { walkFixed<map_request_t>(at); }

inline void walk(const laser_scan_t&, LcmLayout& at) {
  at.fixed(2 * 8 + 4 * 8 + 3 * 8).array(sizeof(float));  // utime seq, 4 doubles, laser_pose[3]; ranges
}

inline void walk(const sonar_targets_t&, LcmLayout& at) {
  at.fixed(2 * 8 + 4 + 3 * 8 + 2 * 8).array(encodedElementBytes<sonar_target_t>());  // utime seq id pose[3] 2 doubles
}

inline void walk(const pose_t&, LcmLayout& at) { at.pose(); }

inline void walk(const features_t&, LcmLayout& at) {
  at.fixed(2 * 8).string().fixed(3 * 8);  // utime seq frame sensor_pose[3]
  at.array(encodedElementBytes<line_feature_t>())
      .array(encodedElementBytes<corner_feature_t>())
      .array(encodedElementBytes<point_feature_t>());
  at.fixed(4).array(8);  // num_rejected, break_hints
}

inline void walk(const grid_map_t&, LcmLayout& at) {
  at.fixed(2 * 8).string();  // utime seq frame
  at.fixed(8 + 3 * 8 + 4 + 4 + 1 + 4).string().array(1);  // resolution origin[3] width height encoding scans; source; data
}

inline void walk(const path_t&, LcmLayout& at) {
  at.fixed(2 * 8).string().fixed(8 + 1);  // utime seq frame goal_utime goal_exact
  at.array(8 + 8 + 8 + 8 + 1);            // pose_utime x y theta source, per pose
}

inline void walk(const pose_graph_t&, LcmLayout& at) {
  at.fixed(2 * 8).string();                   // utime seq frame
  at.array(8 + 8 + 3 * 8);                    // node id, utime, pose[3]
  at.array(8 + 8 + 1 + 1 + 3 * 8 + 9 * 8);    // edge from, to, kind, active, measurement, cov
  at.fixed(4 + 8);                            // num_optimizations optimization_seconds
}

inline void walk(const process_status_t&, LcmLayout& at) {
  at.fixed(8).string().string().fixed(4).string().fixed(4 + 3 * 8);  // utime name host pid state restarts counters
  const int32_t kinds = at.count();
  for (int32_t i = 0; i < kinds && at.ok(); ++i) at.string();  // each takes >= 5 bytes: the loop ends with them
  at.elements(kinds, 8).fixed(2 * 8);  // reject_counts, cpu_percent rss_mb
}

inline void walk(const scan_anchors_t&, LcmLayout& at) {
  at.fixed(2 * 8).pose().array(encodedElementBytes<anchor_observation_t>());
}

inline void walk(const slam_map_t&, LcmLayout& at) {
  at.fixed(2 * 8).pose().array(encodedElementBytes<map_feature_t>());
}

inline void walk(const scan_match_t&, LcmLayout& at) {
  at.fixed(3 * 8).string().string();            // utime ref_utime seq method status
  at.fixed(3 * 8 + 9 * 8 + 4 + 4 + 8 + 8);      // pose[3] cov[9] iterations valid_points error_index time_us
}

inline void walk(const grid_request_t&, LcmLayout& at) { at.fixed(8).string(); }

inline void walk(const grid_status_t&, LcmLayout& at) {
  at.fixed(2 * 8).string().string().string();   // utime seq state error out_dir
  at.fixed(8 + 4 + 4 * 8 + 4 * 4 + 3 * 8 + 4 * 4 + 3 * 8);  // written_utime … write_s
  at.string().fixed(8);                         // plan_state plan_length_m
}

/// True when the message in `data` has its type's layout: every string length and array count fits
/// in the bytes that follow it and the fields end at its last byte.
template <typename MsgT>
bool layoutFits(const MsgT& msg, const uint8_t* data, size_t size) {
  LcmLayout at(data, size);
  walk(msg, at);
  return at.fits();
}

/// Decodes `size` bytes at `data` into `msg`; false when they are not a valid MsgT.
template <typename MsgT>
bool decodeLcm(MsgT& msg, const void* data, size_t size) noexcept {
  if (size > static_cast<size_t>(INT_MAX)) return false;
  if (!layoutFits(msg, static_cast<const uint8_t*>(data), size)) return false;
  try {
    return msg.decode(data, 0, static_cast<int>(size)) >= 0;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace polarslam
