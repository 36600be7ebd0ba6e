#include "board_run.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "harmoloc/firmware/signing_startup.hpp"

namespace harmoloc::boards {

void read_memory(long& rss_kb, long& peak_kb) {
  rss_kb = peak_kb = -1;
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (f == nullptr) return;
  char line[256];
  while (std::fgets(line, sizeof line, f) != nullptr) {
    if (std::strncmp(line, "VmRSS:", 6) == 0) rss_kb = std::strtol(line + 6, nullptr, 10);
    if (std::strncmp(line, "VmHWM:", 6) == 0) peak_kb = std::strtol(line + 6, nullptr, 10);
  }
  std::fclose(f);
}

long count_open_fds() {
  std::error_code ec;
  long n = 0;
  for (auto it = std::filesystem::directory_iterator("/proc/self/fd", ec);
       !ec && it != std::filesystem::directory_iterator(); it.increment(ec)) {
    ++n;
  }
  return ec ? -1 : n - 1;  // the iterator's own descriptor
}

std::string start_signing(const firmware::FirmwareConfig& config,
                          firmware::LocalizationCycle& cycle, drivers::RecordFile& store) {
  const auto wall_us =
      static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                     std::chrono::system_clock::now().time_since_epoch())
                                     .count());
  if (!config.link.signing_peer_clock) cycle.set_signing_time(wall_us);
  if (!config.link.has_signing_key) return "";
  firmware::SigningStartup signing;
  if (std::string e = firmware::start_signing_state(
          config.link, firmware::mavlink::signing_timestamp_from_unix_us(wall_us), signing);
      !e.empty()) {
    return e;
  }
  store.start(config.link.signing_state_file, signing.durable);
  cycle.restore_signing_state(signing.restored, &store, signing.durable);
  return "";
}

void finish_signing(const firmware::FirmwareConfig& config,
                    const firmware::LocalizationCycle& cycle, drivers::RecordFile& store,
                    firmware::RunCounters& run) {
  if (!config.link.has_signing_key) return;
  store.stop();
  if (const std::string e = firmware::write_signing_state(config.link, cycle.final_signing_state());
      !e.empty()) {
    std::fprintf(stderr, "harmoloc: %s\n", e.c_str());
    ++run.outputs_failed;
  }
}

void write_run_stats(const firmware::LocalizationCycle& cycle, const std::string& stats_path,
                     firmware::RunCounters& run) {
  if (stats_path.empty()) return;
  if (const std::string e = firmware::write_stats(stats_path, firmware::stats_json(cycle, run));
      !e.empty()) {
    std::fprintf(stderr, "harmoloc: %s\n", e.c_str());
    ++run.outputs_failed;
  }
}

}  // namespace harmoloc::boards
