#include "stats_dumper.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>

namespace harmoloc::boards {

std::string StatsDumper::start(const std::string& path, bool quiet) {
  path_ = path;
  quiet_ = quiet;
  pending_ = std::make_unique<firmware::StatsSnapshot>();
  writing_ = std::make_unique<firmware::StatsSnapshot>();
  try {
    thread_ = std::thread([this] { writer(); });
  } catch (const std::system_error& e) {
    return std::string("cannot start the stats writer thread (") + e.what() + ")";
  }
  return {};
}

bool StatsDumper::request(const firmware::LocalizationCycle& cycle,
                          const firmware::RunCounters& run) {
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock() || has_pending_) return false;
  firmware::take_snapshot(cycle, run, *pending_);
  pending_->run.ended = "running";
  has_pending_ = true;
  lock.unlock();
  wake_.notify_one();
  return true;
}

void StatsDumper::stop() {
  if (!thread_.joinable()) return;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

std::uint64_t StatsDumper::written() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return written_;
}

std::uint64_t StatsDumper::failed() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return failed_;
}

void StatsDumper::writer() {
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return has_pending_ || stopping_; });
      if (!has_pending_) return;  // stopping, nothing left to write
      std::swap(pending_, writing_);
      has_pending_ = false;
    }
    // Outside the lock: the run loop may hand over the next snapshot meanwhile.
    const std::string tmp = path_ + ".tmp";
    std::string error = firmware::write_stats(tmp, firmware::stats_json(*writing_));
    if (error.empty() && std::rename(tmp.c_str(), path_.c_str()) != 0)
      error = path_ + ": cannot replace (" + std::strerror(errno) + ")";
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      ++(error.empty() ? written_ : failed_);
    }
    if (!error.empty()) {
      std::remove(tmp.c_str());
      std::fprintf(stderr, "harmoloc: stats on request: %s\n", error.c_str());
    } else if (!quiet_) {
      std::fprintf(stderr, "harmoloc: stats written to %s (on request, after %llu cycles)\n",
                   path_.c_str(), static_cast<unsigned long long>(writing_->counters.cycles));
    }
  }
}

}  // namespace harmoloc::boards
