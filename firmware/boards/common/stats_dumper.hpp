#pragma once
/// @file The stats file on request while the firmware runs (SIGUSR1, `systemctl kill -s USR1
/// harmoloc`): the run loop copies the counters into a snapshot reserved at start-up
/// (firmware::take_snapshot, no allocation) and a writer thread turns it into the file, so the
/// cycle never waits for the disk or allocates. The file is replaced atomically (written beside
/// it, then renamed): a reader sees the previous stats or the new ones, never half a file.
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "harmoloc/firmware/stats_report.hpp"

namespace harmoloc::boards {

class StatsDumper {
 public:
  StatsDumper() = default;
  StatsDumper(const StatsDumper&) = delete;
  StatsDumper& operator=(const StatsDumper&) = delete;
  ~StatsDumper() { stop(); }

  /// Start-up: reserves the snapshots and starts the writer for @p path. Returns "" or why not.
  std::string start(const std::string& path, bool quiet);
  bool running() const { return thread_.joinable(); }

  /// In the run loop: hands the writer a snapshot of @p cycle and @p run. Never blocks or
  /// allocates; false when the writer is still busy with the previous one (ask again later).
  bool request(const firmware::LocalizationCycle& cycle, const firmware::RunCounters& run);

  /// Waits for a pending snapshot to be written, then ends the writer.
  void stop();

  std::uint64_t written() const;
  std::uint64_t failed() const;

 private:
  void writer();

  std::string path_;
  bool quiet_ = false;
  std::unique_ptr<firmware::StatsSnapshot> pending_, writing_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool has_pending_ = false, stopping_ = false;
  std::uint64_t written_ = 0, failed_ = 0;
  std::thread thread_;
};

}  // namespace harmoloc::boards
