#include "harmoloc/drivers/input_file.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace harmoloc::drivers {

namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "not a regular file (a directory)";
  if (S_ISFIFO(mode)) return "not a regular file (a FIFO)";
  if (S_ISCHR(mode)) return "not a regular file (a character device)";
  if (S_ISBLK(mode)) return "not a regular file (a block device)";
  if (S_ISSOCK(mode)) return "not a regular file (a socket)";
  return "not a regular file";
}

}  // namespace

int open_regular_file(const char* path, const char** why) {
  const int fd = ::open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    *why = std::strerror(errno);
    return -1;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    *why = std::strerror(errno);
    ::close(fd);
    return -1;
  }
  if (!S_ISREG(st.st_mode)) {
    *why = kind_of(st.st_mode);
    ::close(fd);
    return -1;
  }
  return fd;
}

std::string read_regular_file(const std::string& path, std::size_t max_bytes, std::string& out) {
  out.clear();
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) return std::string("cannot open (") + std::strerror(errno) + ")";
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    const char* why = ::fstat(fd, &st) != 0 ? std::strerror(errno) : kind_of(st.st_mode);
    ::close(fd);
    return why;
  }
  const auto too_big = [max_bytes](unsigned long long size) {
    return std::to_string(size) + " bytes, more than the " + std::to_string(max_bytes) +
           " this file may have";
  };
  if (static_cast<unsigned long long>(st.st_size) > max_bytes) {
    ::close(fd);
    return too_big(static_cast<unsigned long long>(st.st_size));
  }
  // Read up to one byte past the cap: a file that grows after fstat is still caught.
  out.resize(std::min<std::size_t>(static_cast<std::size_t>(st.st_size), max_bytes) + 1U);
  std::size_t got = 0;
  std::string error;
  for (;;) {
    if (got == out.size()) {
      if (out.size() > max_bytes) break;
      out.resize(std::min(max_bytes + 1U, out.size() * 2U + 4096U));
    }
    const ssize_t n = ::read(fd, out.data() + got, out.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      error = std::strerror(errno);
      break;
    }
    if (n == 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  if (!error.empty()) {
    out.clear();
    return "read error: " + error;
  }
  if (got > max_bytes) {
    out.clear();
    return too_big(got) + " (it grew while being read)";
  }
  out.resize(got);
  return {};
}

std::string check_toml_nesting(std::string_view t, std::size_t max_depth) {
  // The structure only: where a key starts, its dotted parts, table headers, and the brackets of
  // arrays and inline tables; strings and comments are skipped whole.
  struct Open {
    bool table;         // an inline table (keys inside), else an array (values inside)
    std::size_t depth;  // nesting of what is inside it
  };
  std::vector<Open> open;
  std::size_t line = 1;
  std::size_t header_depth = 0;  // parts of the [table] or [[array of tables]] header in force
  bool in_key = true;            // a key may start here (a new line, '{' or ',' in a table)
  bool line_start = true;
  std::size_t parts = 1;        // parts of the key being read
  std::size_t value_depth = 0;  // nesting of the value being read
  const auto deep = [&](std::size_t depth) {
    return "line " + std::to_string(line) + ": nested " + std::to_string(depth) +
           " deep (dotted keys, tables and arrays), more than the " + std::to_string(max_depth) +
           " allowed";
  };
  const std::size_t n = t.size();
  std::size_t i = 0;
  // Skips the string opening at i (a basic or literal string, one line or three quotes).
  const auto skip_string = [&]() {
    const char q = t[i];
    const bool triple = i + 2 < n && t[i + 1] == q && t[i + 2] == q;
    i += triple ? 3 : 1;
    while (i < n) {
      const char c = t[i];
      if (c == '\n') {
        ++line;
        if (!triple) return;  // unterminated: toml++ reports it
      }
      if (q == '"' && c == '\\') {
        if (i + 1 < n && t[i + 1] == '\n') ++line;
        i += 2;
        continue;
      }
      if (c == q) {
        if (!triple) {
          ++i;
          return;
        }
        if (i + 2 < n && t[i + 1] == q && t[i + 2] == q) {
          i += 3;
          while (i < n && t[i] == q) ++i;  // up to two quotes may close the content
          return;
        }
      }
      ++i;
    }
  };
  while (i < n) {
    const char c = t[i];
    if (c == '\n') {
      ++line;
      ++i;
      if (open.empty()) {
        in_key = true;
        line_start = true;
        parts = 1;
      }
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r') {
      ++i;
      continue;
    }
    if (c == '#') {
      while (i < n && t[i] != '\n') ++i;
      continue;
    }
    if (c == '"' || c == '\'') {
      skip_string();
      line_start = false;
      continue;
    }
    if (line_start && open.empty() && c == '[') {
      // A table header: [a.b.c] or [[a.b.c]].
      ++i;
      if (i < n && t[i] == '[') ++i;
      std::size_t header_parts = 1;
      while (i < n && t[i] != ']' && t[i] != '\n') {
        if (t[i] == '"' || t[i] == '\'') {
          skip_string();
          continue;
        }
        if (t[i] == '.') ++header_parts;
        ++i;
      }
      if (header_parts > max_depth) return deep(header_parts);
      header_depth = header_parts;
      while (i < n && t[i] == ']') ++i;
      line_start = false;
      in_key = false;
      continue;
    }
    line_start = false;
    if (in_key) {
      if (c == '.') {
        ++parts;
      } else if (c == '=') {
        const std::size_t base = open.empty() ? header_depth : open.back().depth;
        value_depth = base + parts;
        if (value_depth > max_depth) return deep(value_depth);
        in_key = false;
      } else if (c == '}' && !open.empty() && open.back().table) {
        open.pop_back();  // an empty inline table
        in_key = false;
        if (!open.empty()) value_depth = open.back().depth;
      }
      ++i;
      continue;
    }
    switch (c) {
      case '[':
      case '{': {
        // An array's elements are one level down; an inline table is the value its key already
        // counted (its own keys count their parts).
        const std::size_t depth = c == '[' ? value_depth + 1 : value_depth;
        if (depth > max_depth) return deep(depth);
        open.push_back(Open{c == '{', depth});
        value_depth = depth;
        if (c == '{') {
          in_key = true;
          parts = 1;
        }
        break;
      }
      case ']':
      case '}':
        if (!open.empty()) open.pop_back();
        if (!open.empty()) value_depth = open.back().depth;
        break;
      case ',':
        if (!open.empty() && open.back().table) {
          in_key = true;
          parts = 1;
        } else if (!open.empty()) {
          value_depth = open.back().depth;
        }
        break;
      default:
        break;
    }
    ++i;
  }
  return {};
}

std::string check_inside(const std::string& dir, const std::string& relative) {
  namespace fs = std::filesystem;
  const fs::path rel(relative);
  if (relative.empty()) return "is empty";
  if (rel.is_absolute()) return "must be a path relative to the folder, not an absolute one";
  (void)dir;
  for (const fs::path& part : rel) {
    if (part == "..") return "must stay inside the folder (no '..')";
  }
  return {};
}

}  // namespace harmoloc::drivers
