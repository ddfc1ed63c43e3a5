#include "softkin/solver/baselines/ccx_run.hpp"
#include "softkin/solver/common/stopwatch.hpp"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

namespace softkin {
namespace fs = std::filesystem;

std::string FindCcx() {
  const char* path = std::getenv("PATH");
  if (!path) return "";
  std::stringstream ss(path);
  std::string dir;
  while (std::getline(ss, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path p = fs::path(dir) / "ccx";
    if (::access(p.c_str(), X_OK) == 0) return p.string();
  }
  return "";
}

std::string CcxMissingMessage() {
  return "ccx (CalculiX) is not installed or not on PATH; install the Debian package "
         "calculix-ccx (scripts/setup.sh does)";
}

int CountConvergedIncrements(const std::string& sta) {
  std::ifstream in(sta);
  int n = 0;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    long step, inc;
    std::string att;
    if (ss >> step >> inc >> att && !att.empty() && att.back() != 'U' &&
        att.find_first_not_of("0123456789") == std::string::npos)
      ++n;
  }
  return n;
}

CcxWorkFolder::CcxWorkFolder(bool keep) : keep_(keep) {
  std::string tmpl = (fs::temp_directory_path() / "softkin_ccx_XXXXXX").string();
  if (::mkdtemp(tmpl.data())) path_ = tmpl;
}

CcxWorkFolder::~CcxWorkFolder() {
  std::error_code ec;
  if (!keep_ && !path_.empty()) fs::remove_all(path_, ec);
}

namespace {

using Clock = std::chrono::steady_clock;
/// Starts `ccx -i job` in folder `work` (no shell), its output going to `log`; returns the child's
/// pid, or -1 if fork failed.
pid_t StartCcx(const std::string& ccx, const fs::path& work, const std::string& log) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  if (::chdir(work.c_str()) != 0) ::_exit(126);
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0) {
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    ::close(fd);
  }
  ::setenv("OMP_NUM_THREADS", "2", 0);
  char* const argv[] = {const_cast<char*>("ccx"), const_cast<char*>("-i"), const_cast<char*>("job"),
                        nullptr};
  ::execv(ccx.c_str(), argv);
  ::_exit(127);
}

/// The last line of file `log` that mentions an error ("" if none).
std::string LastErrorLine(const std::string& log) {
  std::ifstream lg(log);
  std::string line, last;
  while (std::getline(lg, line))
    if (line.find("ERROR") != std::string::npos || line.find("error") != std::string::npos)
      last = line;
  return last;
}

}  // namespace

CcxRun RunCcxJob(const std::string& ccx, const fs::path& work, double time_limit_s,
                 Clock::time_point t0) {
  CcxRun run;
  const std::string log = (work / "ccx.log").string();
  const pid_t pid = StartCcx(ccx, work, log);
  if (pid < 0) {
    run.last_error = "fork failed";
    return run;
  }
  run.started = true;
  int wstatus = 0;
  // Time-stamp each converged increment as it appears in job.sta (re-read only when it grows).
  const std::string sta = (work / "job.sta").string();
  std::uintmax_t sta_size = 0;
  auto poll_sta = [&]() {
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(sta, ec);
    if (ec || size == sta_size) return;
    sta_size = size;
    const int n = CountConvergedIncrements(sta);
    const double now = Seconds(t0, Clock::now());
    while (static_cast<int>(run.increment_wall_s.size()) < n) run.increment_wall_s.push_back(now);
  };
  for (;;) {
    const pid_t w = ::waitpid(pid, &wstatus, WNOHANG);
    poll_sta();
    if (w == pid) break;
    if (w < 0) {
      run.last_error = "waitpid failed";
      return run;
    }
    if (time_limit_s > 0 && Seconds(t0, Clock::now()) > time_limit_s) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &wstatus, 0);
      run.timed_out = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  run.last_error = LastErrorLine(log);
  return run;
}

}  // namespace softkin
