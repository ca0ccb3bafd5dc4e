#include "tests/testing/pathd_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/string_view.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"

namespace pathd::testing {
namespace {

// The end of a log, for error messages.
std::string Tail(const std::string& text) {
  constexpr size_t kTail = 4000;
  return text.size() <= kTail ? text : "..." + text.substr(text.size() - kTail);
}

}  // namespace

PathdProcess::PathdProcess(PathdProcessOptions options)
    : options_(std::move(options)) {
  std::vector<std::string> argv = {options_.binary};
  if (!options_.address.empty()) argv.push_back("--address=" + options_.address);
  argv.insert(argv.end(), options_.flags.begin(), options_.flags.end());
  int out[2];
  if (!MakePipe(out)) {
    status_ = absl::InternalError(absl::StrCat("pipe: ", strerror(errno)));
    return;
  }
  int log_fd = -1;
  if (!options_.log_file.empty()) {
    log_fd = open(options_.log_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC,
                  0644);
    if (log_fd < 0) {
      status_ = absl::InternalError(
          absl::StrCat("cannot open ", options_.log_file.string(), ": ", strerror(errno)));
      close(out[0]);
      close(out[1]);
      return;
    }
  }
  pid_ = Spawn(argv, options_.extra_env, out[1], log_fd, /*die_with_parent=*/true);
  const int spawn_errno = errno;
  close(out[1]);
  if (log_fd >= 0) close(log_fd);
  stdout_fd_ = out[0];
  if (pid_ < 0) {
    status_ = absl::InternalError(absl::StrCat("fork: ", strerror(spawn_errno)));
    Finish(kKilledBySignal);
    return;
  }
  ReadListeningLine();
}

PathdProcess::~PathdProcess() {
  if (pid_ > 0) {
    Kill();
  } else {
    Finish(exit_code_);
  }
}

void PathdProcess::ReadListeningLine() {
  std::string line;
  const absl::Time deadline = absl::Now() + options_.bound;
  while (line.empty() || line.back() != '\n') {
    if (absl::Now() >= deadline) {
      status_ = absl::DeadlineExceededError(absl::StrCat(
          options_.binary, " printed no listening line within ",
          absl::FormatDuration(options_.bound), "; got '", line, "'\n", Tail(Log())));
      return;
    }
    pollfd p = {stdout_fd_, POLLIN, 0};
    if (poll(&p, 1, 1000) <= 0) continue;
    char c;
    const ssize_t n = read(stdout_fd_, &c, 1);
    if (n < 0 && errno == EINTR) continue;
    if (n != 1) {
      // stdout closed: the daemon is on its way out (a bad flag, a port in use).
      const int code = WaitForExitWithin(pid_, options_.bound);
      Finish(code);
      status_ = absl::UnavailableError(absl::StrCat(
          options_.binary, " exited (code ", code, ") before listening; got '", line,
          "'\n", Tail(Log())));
      return;
    }
    line.push_back(c);
  }
  line.pop_back();
  absl::string_view text = line;
  if (!absl::ConsumePrefix(&text, kListeningPrefix)) {
    status_ = absl::InternalError(
        absl::StrCat("unexpected first stdout line of ", options_.binary, ": '", line,
                     "'\n", Tail(Log())));
  } else {
    address_ = std::string(text);
  }
  drain_ = std::thread([this] {
    char buffer[4096];
    while (true) {
      const ssize_t n = read(stdout_fd_, buffer, sizeof(buffer));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      absl::MutexLock lock(&stdout_mu_);
      stdout_after_.append(buffer, static_cast<size_t>(n));
    }
  });
}

void PathdProcess::Finish(int exit_code) {
  exit_code_ = exit_code;
  pid_ = -1;
  if (drain_.joinable()) drain_.join();
  if (stdout_fd_ >= 0) close(stdout_fd_);
  stdout_fd_ = -1;
}

std::string PathdProcess::Log() const {
  if (options_.log_file.empty()) return "";
  std::ifstream in(options_.log_file, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string PathdProcess::WaitForLogLine(const std::vector<std::string>& parts) const {
  const absl::Time deadline = absl::Now() + options_.bound;
  while (absl::Now() < deadline) {
    std::istringstream lines(Log());
    for (std::string line; std::getline(lines, line);) {
      bool all = true;
      for (const std::string& part : parts) all = all && absl::StrContains(line, part);
      if (all) return line;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return "";
}

bool PathdProcess::Running() {
  if (pid_ <= 0) return false;
  const int code = PollExit(pid_);
  if (code == kDidNotExit) return true;
  Finish(code);
  return false;
}

void PathdProcess::Signal(int signal_number) {
  if (pid_ > 0) kill(pid_, signal_number);
}

int PathdProcess::Stop() {
  Signal(SIGTERM);
  return WaitForExit();
}

int PathdProcess::WaitForExit() {
  if (pid_ <= 0) return exit_code_;
  const pid_t pid = pid_;
  const int code = WaitForExitWithin(pid, options_.bound);
  if (code == kDidNotExit) {
    std::fprintf(stderr, "%s (pid %d) still ran after %s: killed it with SIGKILL\n",
                 options_.binary.c_str(), static_cast<int>(pid),
                 absl::FormatDuration(options_.bound).c_str());
  }
  Finish(code);
  return code;
}

void PathdProcess::Kill() {
  if (pid_ <= 0) return;
  kill(pid_, SIGKILL);
  Finish(pathd::testing::WaitForExit(pid_));
}

std::string PathdProcess::StdoutAfterListening() const {
  absl::MutexLock lock(&stdout_mu_);
  return stdout_after_;
}

}  // namespace pathd::testing
