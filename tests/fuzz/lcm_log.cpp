// libFuzzer target: our LCM log reader (processes/common/lcm_log) on arbitrary files, every event
// it yields decoded as a laser scan the way the offline runs do. The reader may refuse the file
// (an exception) or warn, never crash, hang or yield an event longer than the file.
#include <cstdlib>
#include <stdexcept>

#include "common/lcm_convert.hpp"
#include "common/lcm_log.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static polarslam::fuzz::TempFile file(".lcmlog");
  const std::string& path = file.write(data, size);
  try {
    polarslam::LcmLogReader reader(path);
    polarslam::LogEvent event;
    while (reader.next(event)) {
      if (event.data.size() + event.channel.size() > size) std::abort();
      polarslam::laser_scan_t msg;
      polarslam::LaserScan scan;
      if (event.decode(msg)) (void)polarslam::fromLcm(msg, scan);
    }
  } catch (const std::runtime_error&) {
  }
  return 0;
}
