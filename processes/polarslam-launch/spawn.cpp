#include "spawn.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "launch/executable_search.hpp"

namespace polarslam {
namespace {

/// Owned C strings for execve, built before fork: the child may only call async-signal-safe functions.
struct CStrings {
  std::vector<std::string> storage;
  std::vector<char*> pointers;
  explicit CStrings(std::vector<std::string> strings) : storage(std::move(strings)) {
    for (auto& s : storage) pointers.push_back(s.data());
    pointers.push_back(nullptr);
  }
};

std::vector<std::string> environmentStrings(const Environment& env) {
  std::vector<std::string> out;
  for (const auto& [k, v] : env) out.push_back(k + "=" + v);
  return out;
}

[[noreturn]] void execChild(const char* program, char** argv, char** envp, const char* working_dir, int output_fd,
                            int error_fd, pid_t launcher) {
  setpgid(0, 0);
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != launcher) _exit(127);  // the launcher died before prctl took effect
  const int null_fd = open("/dev/null", O_RDONLY);
  const bool ready = null_fd >= 0 && dup2(null_fd, 0) >= 0 && dup2(output_fd, 1) >= 0 && dup2(output_fd, 2) >= 0 &&
                     (!*working_dir || chdir(working_dir) == 0);
  if (ready) {
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    signal(SIGPIPE, SIG_DFL);  // the launcher ignores it; exec keeps ignored signals ignored
    execve(program, argv, envp);
  }
  const int err = errno;
  [[maybe_unused]] const ssize_t n = write(error_fd, &err, sizeof(err));
  _exit(127);
}

}  // namespace

Environment commandEnvironment(const CommandSpec& spec, const Environment& base_env, const std::string& bin_dir) {
  Environment env = base_env;
  for (const auto& [k, v] : spec.environment) env[k] = v;
  const auto path = env.find("PATH");
  const std::string rest = path != env.end() ? path->second : "/usr/local/bin:/usr/bin:/bin";
  if (!bin_dir.empty()) env["PATH"] = bin_dir + ":" + rest;
  return env;
}

SpawnResult spawnCommand(const CommandSpec& spec, const Environment& base_env, const std::string& bin_dir) {
  const Environment env = commandEnvironment(spec, base_env, bin_dir);
  SpawnResult result;
  std::error_code ec;
  if (!spec.working_dir.empty() && !std::filesystem::is_directory(spec.working_dir, ec)) {
    result.error = "working directory '" + spec.working_dir + "' does not exist";
    return result;
  }
  const std::string program = findExecutable(spec.argv[0], env.at("PATH"), spec.working_dir);
  if (program.empty()) {
    const bool is_path = spec.argv[0].find('/') != std::string::npos;
    result.error = is_path ? "'" + spec.argv[0] + "' is not an executable file"
                           : "executable '" + spec.argv[0] + "' not found on PATH";
    result.detail = is_path ? "working directory " + (spec.working_dir.empty() ? "." : spec.working_dir)
                            : "PATH=" + env.at("PATH");
    return result;
  }
  CStrings argv(spec.argv), envp(environmentStrings(env));
  int output[2], errors[2];
  if (pipe2(output, O_CLOEXEC) != 0) {
    result.error = std::string("pipe: ") + std::strerror(errno);
    return result;
  }
  if (pipe2(errors, O_CLOEXEC) != 0) {
    result.error = std::string("pipe: ") + std::strerror(errno);
    close(output[0]);
    close(output[1]);
    return result;
  }
  const pid_t launcher = getpid();
  const pid_t pid = fork();
  if (pid == 0)
    execChild(program.c_str(), argv.pointers.data(), envp.pointers.data(), spec.working_dir.c_str(), output[1],
              errors[1], launcher);
  close(output[1]);
  close(errors[1]);
  if (pid < 0) {
    result.error = std::string("fork: ") + std::strerror(errno);
    close(output[0]);
    close(errors[0]);
    return result;
  }
  setpgid(pid, pid);  // also here, so the group exists before anyone signals it
  int child_errno = 0;
  // exec closes the CLOEXEC write end: 0 bytes means it succeeded.
  ssize_t n;
  do n = read(errors[0], &child_errno, sizeof(child_errno));
  while (n < 0 && errno == EINTR);
  close(errors[0]);
  if (n == static_cast<ssize_t>(sizeof(child_errno))) {
    waitpid(pid, nullptr, 0);
    close(output[0]);
    result.error = "cannot execute " + program + ": " + std::strerror(child_errno);
    return result;
  }
  fcntl(output[0], F_SETFL, fcntl(output[0], F_GETFL) | O_NONBLOCK);
  result.pid = pid;
  result.output_fd = output[0];
  return result;
}

}  // namespace polarslam
