#pragma once
/// @file Real-time set-up of the calling thread, as the Linux Foundation real-time wiki's cyclic
/// application does it: SCHED_FIFO at a priority, CPU affinity, mlockall and a prefaulted stack.
/// Each step is tried on its own; one that is not permitted (no privilege, a container) is
/// reported and the firmware runs on without it.

#include <cstddef>
#include <string>

namespace harmoloc::drivers {

struct RealtimeOptions {
  bool enabled = true;
  int priority = 80;        ///< SCHED_FIFO priority 1..99
  int cpu = -1;             ///< pin to this CPU; -1 leaves affinity alone
  bool lock_memory = true;  ///< mlockall(MCL_CURRENT | MCL_FUTURE)
  std::size_t prefault_stack_kb =
      256;  ///< touch this much stack so the cycle never page-faults on it
};

struct RealtimeReport {
  bool scheduler = false;
  bool affinity = false;
  bool memory_locked = false;
  bool stack_prefaulted = false;
  /// One line for the log: what was applied and what was not, with the reason.
  std::string summary;
};

RealtimeReport apply_realtime(const RealtimeOptions& options);

}  // namespace harmoloc::drivers
