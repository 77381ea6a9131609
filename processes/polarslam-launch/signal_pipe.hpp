#pragma once
// The self-pipe trick: SIGCHLD, SIGINT, SIGTERM, SIGHUP and SIGWINCH become bytes on a pipe that
// the launcher's poll() loop watches, so no work happens inside a signal handler.
#include <vector>

namespace polarslam {

class SignalPipe {
 public:
  SignalPipe();  // installs the handlers; one instance per process
  SignalPipe(const SignalPipe&) = delete;
  SignalPipe& operator=(const SignalPipe&) = delete;
  ~SignalPipe();

  int fd() const;
  /// The signals received since the last call, in order.
  std::vector<int> drain();
};

}  // namespace polarslam
