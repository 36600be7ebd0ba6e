#pragma once
/// @file The command line of every harmoloc program (CLI11), in one place: `--help`, `--version`,
/// and every usage error as one line "TOOL: reason" with exit status 2, as the docs promise
/// (CLI11 itself prints two lines without the tool's name and exits with 105..114). Unsigned
/// options refuse a negative number (CLI11 2.1 reads "--seed -1" as 18446744073709551615).
///
///   CLI::App app{"...", "harmoloc-sim"};
///   ... add options ...
///   if (const auto status = harmoloc::cli::parse(app, argc, argv)) return *status;

#include <cstdio>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#ifndef HARMOLOC_VERSION
#define HARMOLOC_VERSION "unknown"
#endif

namespace harmoloc::cli {

/// Exit status of a usage error (docs/architecture.md).
constexpr int kUsageError = 2;

/// Refuses a value with a leading '-' (for unsigned options).
inline CLI::Validator non_negative() {
  return CLI::Validator(
      [](std::string& value) -> std::string {
        const std::size_t first = value.find_first_not_of(" \t");
        if (first != std::string::npos && value[first] == '-')
          return "must not be negative: " + value;
        return {};
      },
      "", "NON_NEGATIVE");
}

/// The version line: "TOOL VERSION".
inline std::string version_of(const CLI::App& app) {
  return app.get_name() + " " + HARMOLOC_VERSION;
}

/// Parses @p argc / @p argv into @p app, whose name is the tool's. Returns an exit status when
/// the program should end now: 0 after --help or --version (printed on stdout), kUsageError
/// after a usage error (printed on stderr as one line "TOOL: reason"); otherwise nothing.
inline std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  app.set_version_flag("--version", version_of(app), "print the version and exit");
  for (CLI::Option* option : app.get_options()) {
    if (option->get_type_name().rfind("UINT", 0) == 0) option->check(non_negative());
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::fputs(app.help().c_str(), stdout);
    return 0;
  } catch (const CLI::CallForAllHelp&) {
    std::fputs(app.help("", CLI::AppFormatMode::All).c_str(), stdout);
    return 0;
  } catch (const CLI::CallForVersion& e) {
    std::printf("%s\n", e.what());
    return 0;
  } catch (const CLI::ParseError& e) {
    std::string reason = e.what();
    for (char& c : reason) {
      if (c == '\n' || c == '\r') c = ' ';
    }
    while (!reason.empty() && reason.back() == ' ') reason.pop_back();
    std::fprintf(stderr, "%s: %s (see --help)\n", app.get_name().c_str(), reason.c_str());
    return kUsageError;
  }
  return std::nullopt;
}

}  // namespace harmoloc::cli
