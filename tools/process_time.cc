#include "process_time.h"

#include <sched.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace pointdag {

StatusOr<double> ProcessCpuSeconds(const ProcessRun& run) {
  if (run.argv.empty()) return InvalidArgument("no command to time");
  std::vector<char*> argv;
  for (const std::string& a : run.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return IoError("fork failed");
  if (pid == 0) {
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(run.core, &one);
    sched_setaffinity(0, sizeof(one), &one);
    for (const auto& [name, value] : run.env) setenv(name.c_str(), value.c_str(), 1);
    execvp(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid) return IoError("wait4 failed for " + run.argv[0]);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::ostringstream why;
    why << run.argv[0] << (WIFEXITED(status) ? " exited with status " + std::to_string(WEXITSTATUS(status))
                                             : std::string(" was killed by a signal"));
    return IoError(why.str());
  }
  const auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

StatusOr<double> BestProcessCpuSeconds(const ProcessRun& run, int runs) {
  double best = 0;
  for (int i = 0; i < runs; ++i) {
    ASSIGN_OR_RETURN(const double s, ProcessCpuSeconds(run));
    best = i == 0 ? s : std::min(best, s);
  }
  return best;
}

std::string FindExecutable(const std::string& name) {
  namespace fs = std::filesystem;
  const auto runnable = [](const fs::path& p) { return access(p.c_str(), X_OK) == 0 && fs::is_regular_file(p); };
  if (name.find('/') != std::string::npos) return runnable(name) ? name : std::string();
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    if (!dir.empty() && runnable(fs::path(dir) / name)) return (fs::path(dir) / name).string();
  }
  return {};
}

}  // namespace pointdag
