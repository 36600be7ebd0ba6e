#include "format.hpp"

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace harmoloc::sim_host::report_text {

std::string format(const char* fmt, ...) {
  va_list args;
  va_start(args, fmt);
  va_list copy;
  va_copy(copy, args);
  char buffer[512];
  const int n = std::vsnprintf(buffer, sizeof buffer, fmt, args);
  va_end(args);
  std::string out;
  if (n > 0 && static_cast<std::size_t>(n) < sizeof buffer) {
    out.assign(buffer, static_cast<std::size_t>(n));
  } else if (n > 0) {
    out.resize(static_cast<std::size_t>(n) + 1);
    std::vsnprintf(out.data(), out.size(), fmt, copy);
    out.resize(static_cast<std::size_t>(n));
  }
  va_end(copy);
  return out;
}

std::string cm(double metres) {
  return format("%.2f cm", metres * 100.0);
}

std::string duration(double us, bool micro_sign) {
  const char* unit = micro_sign ? "µs" : "us";
  if (!std::isfinite(us)) return "n/a";
  if (us < 10.0) return format("%.1f %s", us, unit);
  if (us < 1000.0) return format("%.0f %s", us, unit);
  if (us < 10000.0) return format("%.2f ms", us / 1000.0);
  return format("%.1f ms", us / 1000.0);
}

std::string cell(double value, int decimals) {
  if (!std::isfinite(value)) return "n/a";
  return format("%.*f", decimals, value);
}

std::string budget(double us) {
  return format("%g ms", us / 1000.0);
}

std::string seconds(double s) {
  return format("%g s", s);
}

void write_file(const std::filesystem::path& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
  out << content;
  out.close();
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

}  // namespace harmoloc::sim_host::report_text
