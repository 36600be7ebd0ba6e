#pragma once
/// @file Text formatting shared by the report's summaries, plots and page, so that a number reads
/// the same wherever it appears (the terminal, the JSON's neighbours, the SVGs, the HTML).

#include <filesystem>
#include <string>

namespace harmoloc::sim_host::report_text {

/// printf into a std::string: the report's layouts are column- and precision-driven.
std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

std::string cm(double metres);

/// A duration in microseconds, in the unit that reads best ("812 us", "1.20 ms", "15.0 ms").
/// Plots and the page spell microseconds "µs" (@p micro_sign); the terminal gets plain "us".
std::string duration(double us, bool micro_sign = false);

/// A number for a table cell: "n/a" when it is NaN.
std::string cell(double value, int decimals);

/// The budget as configured ("15 ms", "12.5 ms").
std::string budget(double us);

std::string seconds(double s);

/// Writes @p content to @p path whole; std::runtime_error("PATH: cannot write" or "PATH: write
/// failed") otherwise.
void write_file(const std::filesystem::path& path, const std::string& content);

}  // namespace harmoloc::sim_host::report_text
