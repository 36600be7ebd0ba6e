#pragma once
/// @file Stopping cleanly on a signal (both board mains): SIGTERM, SIGINT and SIGHUP only set a
/// flag that the main loop reads at the next cycle boundary, after which every output is flushed
/// and closed and the stats are written; SIGPIPE is ignored, so a link whose reader went away
/// fails its writes (counted as link errors) instead of killing the process. A signal that was
/// ignored when the program started (nohup, a background job) stays ignored.

namespace harmoloc::drivers {

/// Installs the handlers. Call once at start-up.
void install_stop_signals();

/// The signal that asked the program to stop, or 0.
int stop_signal();

/// "SIGTERM", "SIGINT", "SIGHUP" or "signal N".
const char* signal_name(int signal);

/// SIGUSR1 asks for the stats file without stopping (the Linux board with --stats): the handler
/// only sets a flag, which take_stats_request() reads and clears at a cycle boundary. Requests
/// that arrive before the last one was taken are one request.
void install_stats_signal();
bool take_stats_request();

}  // namespace harmoloc::drivers
