#pragma once
/// @file The one error type of the run report's inputs, shared by its stats reader and the
/// report itself so that a tool catches one type and prints its one-line message.

#include <stdexcept>

namespace harmoloc::sim_host {

/// Bad input to the report (no overlap in time, malformed stats, ...). The message is one line.
class ReportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace harmoloc::sim_host
