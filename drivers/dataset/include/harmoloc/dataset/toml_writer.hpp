#pragma once
/// @file TOML files the project writes (metadata.toml, scenario.toml, a scene's harmoloc.toml),
/// built as toml++ values and written in the order a person reads them.
///
/// toml++ 3.3's own printer sorts the keys of a table and, built with GCC (no floating-point
/// std::to_chars in toml++'s configuration), prints a double with 17 digits: 0.05 comes out as
/// 0.050000000000000003. TomlWriter keeps toml++ for the values (string escaping, integer
/// formats, the document as a toml::table) and writes them itself in the order they were set:
/// - a double in its shortest form that reads back as the same double (0.05), and a whole number
///   within +-2^53 as an integer (`ticks_per_rev = 2048`; every reader of these files takes an
///   integer where a number is expected);
/// - strings as TOML basic strings ("..."), escaped by toml++;
/// - arrays inline, `[1, 2.5]`;
/// - a comment block first (toml++ writes no comments).
/// document() is the same content as a toml::table: toml::parse(text()) equals it.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <toml++/toml.h>

namespace harmoloc::dataset {

/// The double whose shortest decimal is @p value's shortest decimal: a float threshold of 37.3
/// written as 37.3, not 37.29999923706055 (reads back as the same float).
double decimal_of(float value);

/// Appends @p value to @p array as TomlWriter writes a number (an integer when whole).
void push_number(toml::array& array, double value);

template <std::size_t N>
toml::array number_array(const std::array<double, N>& values) {
  toml::array out;
  for (const double v : values) push_number(out, v);
  return out;
}

template <std::size_t N>
toml::array number_arrays(const std::vector<std::array<double, N>>& list) {
  toml::array out;
  for (const auto& values : list) out.push_back(number_array(values));
  return out;
}

class TomlWriter {
 public:
  /// @p comment: lines written first, each as "# line" (a control character in it becomes a
  /// space, so that a scene's name cannot end the comment).
  explicit TomlWriter(std::string_view comment = {});

  /// The keys set next go to `[name]`.
  TomlWriter& table(std::string_view name);
  /// The keys set next go to a new entry of `[[name]]`.
  TomlWriter& array_table(std::string_view name);

  /// `key = value` in the current table: a bool, an integer, a double or float (see the file
  /// comment), a string or a toml::array. Setting a key twice keeps the first place, last value.
  template <typename T>
  TomlWriter& set(std::string_view key, const T& value) {
    if constexpr (std::is_same_v<T, bool>) {
      put(key, toml::value<bool>(value));
    } else if constexpr (std::is_integral_v<T>) {
      put(key, toml::value<std::int64_t>(checked_integer(key, value)));
    } else if constexpr (std::is_same_v<T, float>) {
      set_number(key, decimal_of(value));
    } else if constexpr (std::is_floating_point_v<T>) {
      set_number(key, static_cast<double>(value));
    } else if constexpr (std::is_same_v<T, toml::array>) {
      put(key, toml::array(value));
    } else {
      put(key, toml::value<std::string>(std::string(std::string_view(value))));
    }
    return *this;
  }
  /// An integer written in hexadecimal (`can_id = 0x18FF0001`).
  TomlWriter& set_hex(std::string_view key, std::int64_t value);

  /// The file's text.
  std::string text() const;
  /// What text() reads back as.
  toml::table document() const;

 private:
  struct Section {
    std::string name;  ///< empty: the top level
    bool array = false;
    toml::table values;
    std::vector<std::string> order;
  };

  template <typename V>
  void put(std::string_view key, V&& value) {
    Section& s = sections_.back();
    if (s.values.insert_or_assign(key, std::forward<V>(value)).second) s.order.emplace_back(key);
  }
  void set_number(std::string_view key, double value);

  template <typename T>
  static std::int64_t checked_integer(std::string_view key, T value) {
    if constexpr (std::is_unsigned_v<T> && sizeof(T) >= sizeof(std::int64_t)) {
      if (value > static_cast<T>(INT64_MAX)) too_large(key, static_cast<std::uint64_t>(value));
    }
    return static_cast<std::int64_t>(value);
  }
  [[noreturn]] static void too_large(std::string_view key, std::uint64_t value);

  std::string comment_;
  std::vector<Section> sections_;
};

}  // namespace harmoloc::dataset
