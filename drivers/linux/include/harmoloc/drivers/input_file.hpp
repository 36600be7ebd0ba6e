#pragma once
/// @file Reading the files the firmware and the tools are given (config, map, dataset files,
/// signing key and state, labels, stats): a regular file only, its size checked against a cap
/// before a byte is read, opened non-blocking, so that a directory, a FIFO, a device such as
/// /dev/zero or a file of gigabytes stops start-up with one line instead of blocking it or
/// filling the memory. And a check of a TOML text's nesting before toml++ parses it: toml++
/// recurses once per part of a dotted key with no bound, so a 100 KB key of 50,000 parts ends
/// the process on a stack overflow (docs/reliability.md).

#include <cstddef>
#include <string>
#include <string_view>

namespace harmoloc::drivers {

/// Size caps of the files read at start-up (bytes). A config or metadata file is a few KB; the
/// caps leave wide room and stop anything that is not such a file.
namespace input_limits {
constexpr std::size_t kTomlBytes = 256U * 1024U;  ///< config, metadata, scenario
constexpr std::size_t kKeyBytes = 4096U;          ///< a signing key (32 bytes or 64 hex digits)
constexpr std::size_t kStateBytes = 64U * 1024U;  ///< the signing state
/// A recording's text files (frame index, encoder logs, area logs, TUM trajectories and labels):
/// an hour of a 100 Hz encoder log is about 15 MB.
constexpr std::size_t kRecordingBytes = 512U * 1024U * 1024U;
constexpr std::size_t kStatsBytes = 16U * 1024U * 1024U;  ///< a stats JSON
/// Dotted-key parts, tables and arrays inside each other in a TOML file.
constexpr std::size_t kTomlDepth = 32U;
}  // namespace input_limits

/// Opens @p path for reading if it is a regular file: open(2) with O_NONBLOCK (a FIFO or device
/// put in its place cannot block the open), then fstat(2) on the descriptor (what was opened is
/// what is checked). Returns the descriptor, or -1 with @p why set to a static reason. Allocates
/// nothing: the cycle may use it.
int open_regular_file(const char* path, const char** why);

/// Reads the whole regular file @p path into @p out if it holds at most @p max_bytes. Returns an
/// empty string, or the reason ("not a regular file (a directory)", "N bytes, more than the M
/// this file may have", the system's message), without the path.
std::string read_regular_file(const std::string& path, std::size_t max_bytes, std::string& out);

/// Checks that @p toml nests at most @p max_depth deep: the parts of a table header, plus those
/// of a dotted key under it, plus the inline tables and arrays a value sits in. A conservative
/// scan (strings and comments skipped), not a parser: it never counts less than toml++ nests;
/// syntax errors are left to toml++. Returns an empty string, or "line N: ..." saying how deep.
std::string check_toml_nesting(std::string_view toml,
                               std::size_t max_depth = input_limits::kTomlDepth);

/// Whether @p relative names a path inside the folder @p dir by its name: relative, with no ".."
/// part. A symbolic link inside the folder is followed (datasets share frames that way); what it
/// leads to must still be a regular file when it is read. Returns an empty string, or the reason.
std::string check_inside(const std::string& dir, const std::string& relative);

}  // namespace harmoloc::drivers
