#include "startup.h"

#include <arpa/inet.h>
#include <sys/resource.h>

#include <fstream>
#include <set>

namespace pointdag::server {

StatusOr<std::string> ReadTokenFile(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) return IoError("cannot read the token file " + file.string());
  std::string token;
  std::getline(in, token);
  while (!token.empty() && std::isspace(static_cast<unsigned char>(token.back()))) token.pop_back();
  if (token.empty()) return InvalidArgument("the token file " + file.string() + " has no token on its first line");
  return token;
}

Status CheckExposure(const DaemonConfig& config, bool no_token) {
  if (!config.token.empty() || no_token) return Status::Ok();
  in_addr v4{};
  in6_addr v6{};
  const bool loopback = (inet_pton(AF_INET, config.host.c_str(), &v4) == 1 && (ntohl(v4.s_addr) >> 24) == 127) ||
                        (inet_pton(AF_INET6, config.host.c_str(), &v6) == 1 && IN6_IS_ADDR_LOOPBACK(&v6));
  if (loopback) return Status::Ok();
  return InvalidArgument("refusing to listen on " + config.host +
                         " without a token: anyone who reaches it could upload and delete. Set a token (token, "
                         "token_file, --token, --token-file or POINTDAGD_TOKEN) or pass --no-token to mean it");
}

size_t SweepLeftovers(Store& store, const std::filesystem::path& data_dir, bool keep_spill) {
  // By file name: the data folder may be spelt differently from one start to the next.
  std::set<std::filesystem::path> in_use;
  const auto jobs = store.JobsInStates({"queued", "running"});
  if (jobs.ok()) {
    for (const JobRecord& job : *jobs) {
      if (!job.upload_path.empty()) in_use.insert(std::filesystem::path(job.upload_path).filename());
    }
  }
  size_t removed = 0;
  std::error_code ec;
  if (!keep_spill) {
    for (const auto& entry : std::filesystem::directory_iterator(data_dir / "spill", ec)) {
      removed += std::filesystem::remove_all(entry.path(), ec) > 0 ? 1 : 0;
    }
  }
  if (!jobs.ok()) return removed;  // which uploads are in use is unknown: keep them all
  for (const auto& entry : std::filesystem::directory_iterator(data_dir / "uploads", ec)) {
    if (in_use.count(entry.path().filename())) continue;
    removed += std::filesystem::remove_all(entry.path(), ec) > 0 ? 1 : 0;
  }
  return removed;
}

void RaiseOpenFileLimit() {
  rlimit limit{};
  if (getrlimit(RLIMIT_NOFILE, &limit) != 0 || limit.rlim_cur >= limit.rlim_max) return;
  limit.rlim_cur = limit.rlim_max;
  (void)setrlimit(RLIMIT_NOFILE, &limit);
}

}  // namespace pointdag::server
