#pragma once
// A string as a TOML basic string (quoted, with \ " and control characters escaped), for the
// files the simulator writes: a name with a quote must still read back.
#include <cstdio>
#include <string>

namespace harmoloc::dataset {

inline std::string toml_string(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || u == 0x7F) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04X", u);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace harmoloc::dataset
