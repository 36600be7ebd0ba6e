#include "harmoloc/drivers/realtime_setup.hpp"

#include <cerrno>
#include <cstring>

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

namespace harmoloc::drivers {

namespace {

// Touches the stack below the caller so its pages are mapped (and locked) before the cycle runs.
__attribute__((noinline)) void prefault_stack(std::size_t bytes) {
  volatile unsigned char* block = static_cast<volatile unsigned char*>(__builtin_alloca(bytes));
  for (std::size_t i = 0; i < bytes; i += 4096) block[i] = 0;
}

}  // namespace

RealtimeReport apply_realtime(const RealtimeOptions& o) {
  RealtimeReport r;
  if (!o.enabled) {
    r.summary = "real-time set-up disabled in the config";
    return r;
  }
  std::string applied, missing;
  auto note = [](std::string& list, const std::string& what) {
    list += (list.empty() ? "" : ", ") + what;
  };

  if (o.lock_memory) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      r.memory_locked = true;
      note(applied, "mlockall");
    } else {
      note(missing, std::string("mlockall (") + std::strerror(errno) + ")");
    }
  }
  if (o.prefault_stack_kb > 0) {
    prefault_stack(o.prefault_stack_kb * 1024U);
    r.stack_prefaulted = true;
    note(applied, "stack prefaulted " + std::to_string(o.prefault_stack_kb) + " KiB");
  }
  if (o.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<unsigned>(o.cpu), &set);
    const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
    if (rc == 0) {
      r.affinity = true;
      note(applied, "CPU " + std::to_string(o.cpu));
    } else {
      note(missing, "CPU " + std::to_string(o.cpu) + " affinity (" + std::strerror(rc) + ")");
    }
  }
  sched_param param{};
  param.sched_priority = o.priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (rc == 0) {
    r.scheduler = true;
    note(applied, "SCHED_FIFO " + std::to_string(o.priority));
  } else {
    note(missing, "SCHED_FIFO " + std::to_string(o.priority) + " (" + std::strerror(rc) + ")");
  }
  r.summary = "real-time: " + (applied.empty() ? std::string("nothing applied") : applied) +
              (missing.empty() ? "" : "; not permitted here, running without: " + missing);
  return r;
}

}  // namespace harmoloc::drivers
