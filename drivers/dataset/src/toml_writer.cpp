#include "harmoloc/dataset/toml_writer.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace harmoloc::dataset {

namespace {

// Within +-2^53 every whole double is an integer that converts back exactly.
constexpr double kWholeLimit = 9007199254740992.0;

bool whole(double v) {
  return std::isfinite(v) && std::fabs(v) <= kWholeLimit && std::trunc(v) == v &&
         !(v == 0.0 && std::signbit(v));
}

// The shortest form that reads back as the same double, as a TOML float ("2e-05", "1.5",
// "inf"; "1e+22" is a TOML float as it is).
void write_double(std::ostream& out, double v) {
  if (std::isnan(v)) {
    out << "nan";
    return;
  }
  if (std::isinf(v)) {
    out << (v < 0 ? "-inf" : "inf");
    return;
  }
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  const std::string_view text(buf, static_cast<std::size_t>(r.ptr - buf));
  out << text;
  if (text.find_first_of(".e") == std::string_view::npos) out << ".0";
}

constexpr auto kFormat =
    toml::format_flags::allow_hexadecimal_integers | toml::format_flags::allow_unicode_strings;

// A key as TOML writes it: bare when it can be, quoted otherwise.
void write_key(std::ostream& out, std::string_view key) {
  bool bare = !key.empty();
  for (const char c : key) {
    bare = bare && ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-');
  }
  if (bare)
    out << key;
  else
    out << toml::toml_formatter{toml::value<std::string>(std::string(key)), kFormat};
}

void write_value(std::ostream& out, const toml::node& node) {
  if (const auto* d = node.as_floating_point()) {
    write_double(out, d->get());
  } else if (const auto* a = node.as_array()) {
    out << '[';
    for (std::size_t i = 0; i < a->size(); ++i) {
      if (i > 0) out << ", ";
      write_value(out, *a->get(i));
    }
    out << ']';
  } else if (const auto* t = node.as_table()) {
    out << '{';
    bool first = true;
    for (const auto& [key, value] : *t) {
      out << (first ? " " : ", ");
      write_key(out, key.str());
      out << " = ";
      write_value(out, value);
      first = false;
    }
    out << (first ? "}" : " }");
  } else {
    node.visit([&out](const auto& v) { out << toml::toml_formatter{v, kFormat}; });
  }
}

}  // namespace

double decimal_of(float value) {
  if (!std::isfinite(value)) return static_cast<double>(value);
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf - 1, value);
  *r.ptr = '\0';
  return std::strtod(buf, nullptr);
}

void push_number(toml::array& array, double value) {
  if (whole(value))
    array.push_back(static_cast<std::int64_t>(value));
  else
    array.push_back(value);
}

TomlWriter::TomlWriter(std::string_view comment) : sections_(1) {
  if (comment.empty()) return;
  comment_ = "# ";
  for (const char c : comment) {
    if (c == '\n') {
      comment_ += "\n# ";
    } else {
      const auto u = static_cast<unsigned char>(c);
      comment_ += (u < 0x20 || u == 0x7F) ? ' ' : c;
    }
  }
  comment_ += '\n';
  // "# " alone on a line (an empty line of the comment) without its trailing space.
  for (std::size_t at = 0; (at = comment_.find("# \n", at)) != std::string::npos; ++at)
    comment_.erase(at + 1, 1);
}

TomlWriter& TomlWriter::table(std::string_view name) {
  sections_.push_back(Section{std::string(name), false, {}, {}});
  return *this;
}

TomlWriter& TomlWriter::array_table(std::string_view name) {
  sections_.push_back(Section{std::string(name), true, {}, {}});
  return *this;
}

TomlWriter& TomlWriter::set_hex(std::string_view key, std::int64_t value) {
  put(key, toml::value<std::int64_t>(value));
  sections_.back().values.get(key)->as_integer()->flags(toml::value_flags::format_as_hexadecimal);
  return *this;
}

void TomlWriter::set_number(std::string_view key, double value) {
  if (whole(value))
    put(key, toml::value<std::int64_t>(static_cast<std::int64_t>(value)));
  else
    put(key, toml::value<double>(value));
}

void TomlWriter::too_large(std::string_view key, std::uint64_t value) {
  throw std::runtime_error(std::string(key) + " = " + std::to_string(value) +
                           " does not fit a TOML integer (at most 2^63 - 1)");
}

std::string TomlWriter::text() const {
  std::ostringstream out;
  out << comment_;
  for (std::size_t i = 0; i < sections_.size(); ++i) {
    const Section& s = sections_[i];
    if (i > 0) {
      if (out.tellp() > 0) out << '\n';
      out << (s.array ? "[[" : "[");
      write_key(out, s.name);
      out << (s.array ? "]]" : "]") << '\n';
    }
    for (const std::string& key : s.order) {
      write_key(out, key);
      out << " = ";
      write_value(out, *s.values.get(key));
      out << '\n';
    }
  }
  return out.str();
}

toml::table TomlWriter::document() const {
  toml::table root = sections_.front().values;
  for (std::size_t i = 1; i < sections_.size(); ++i) {
    const Section& s = sections_[i];
    if (s.array) {
      if (root.get(s.name) == nullptr) root.insert(s.name, toml::array{});
      root.get(s.name)->as_array()->push_back(s.values);
    } else {
      root.insert_or_assign(s.name, s.values);
    }
  }
  return root;
}

}  // namespace harmoloc::dataset
